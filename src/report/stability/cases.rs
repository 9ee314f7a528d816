//! The stiff and extreme variants of a scene. The loaded `Scene` is transformed and extended in Rust;
//! only what must go through a loader is written to `DIR/cases/`: OBJ meshes (tiny and zero-area
//! triangles, with the OBJ reader's normal generation) and Radiance .hdr environment maps.

use std::path::Path;

use anyhow::{Context as _, Result};
use glam::{DVec3, EulerRot, Quat, Vec3};

use crate::scene::{
    primitives, Camera, LightKind, Material, Mesh, Node, Object, Primitive, Scene, Transform,
};

/// What a case's image is compared with.
#[derive(Clone, Debug, PartialEq)]
pub enum Against {
    /// Another case (its canonical), on the same backend.
    Case(&'static str),
    /// The same case in pure-RT mode (camera rays instead of the raster
    /// G-buffer) on the same backend: where no scene without the extreme
    /// would show the same image, an independent primary-hit path does.
    Rt,
}

/// A pass condition besides "every pixel finite" (which every case has).
#[derive(Clone, Debug, PartialEq)]
pub enum Check {
    /// PSNR (linear radiance, peak = the comparison's largest value) >= dB.
    PsnrAtLeast(f64),
    /// Largest tone-mapped 8-bit channel difference <= this.
    MaxLdrDiff(u8),
    /// Black share (8-bit 0 in all channels) at most that of the named
    /// case (same backend) plus this many percentage points.
    BlackNotAbove(&'static str, f64),
    /// White share (255 in all channels), likewise.
    WhiteNotAbove(&'static str, f64),
}

impl Check {
    pub fn describe(&self) -> String {
        match self {
            Check::PsnrAtLeast(db) => format!("PSNR >= {db} dB"),
            Check::MaxLdrDiff(d) => format!("max 8-bit difference <= {d}"),
            Check::BlackNotAbove(c, p) => format!("black % <= black % of {c} + {p}"),
            Check::WhiteNotAbove(c, p) => format!("white % <= white % of {c} + {p}"),
        }
    }
}

/// One variant of the scene to render on every backend.
pub struct Case {
    pub name: &'static str,
    pub about: String,
    pub scene: Scene,
    pub camera: Camera,
    /// Max depth and min weight instead of the base settings'.
    pub depth: Option<(u32, f32)>,
    pub against: Against,
    pub checks: Vec<Check>,
}

/// Every case name, in report order (canonicals before their cases).
pub const CASE_NAMES: &[&str] = &[
    "origin",
    "translate-1e3",
    "translate-1e5",
    "translate-1e6",
    "scale-1e-4",
    "scale-1e-3",
    "scale-1e3",
    "scale-1e4",
    "grazing-mirror",
    "origin-rough",
    "ior-1.0",
    "ior-1.0001",
    "ior-1.5",
    "ior-2.42",
    "tir-slab",
    "facing-mirrors",
    "env-map",
    "env-texel-1e5",
    "emissive-65504",
    "emissive-1e6",
    "obj-panel",
    "tiny-triangles",
    "zero-area-triangles",
    "near-wall",
];

/// PSNR the translated and scaled scenes must reach against the origin
/// (issue 18: "render like the origin"). Measured on lavapipe: 129-139 dB
/// on the default scene (320x180; 136-151 at 64x36), 89 on Sponza. The
/// frame is rebased; without the rebase translate-1e3 measured 69.7 dB
/// (max 8-bit difference 4), which 35 dB, the old bar, let pass.
pub const INVARIANT_PSNR: f64 = 80.0;
/// A glass sphere of IOR 1.0001 against none: nearly invisible, not exactly
/// (54.7 dB on Sponza, 57.4 on the default scene at 320x180).
pub const NEAR_INVISIBLE_PSNR: f64 = 50.0;
/// PSNR of hybrid against pure RT where that is the comparison (62.7 dB at
/// the lowest, Sponza at 320x180; 160+ on the default scene at 64x36).
pub const MODE_PSNR: f64 = 50.0;
/// One 1e5 environment texel against the map without it (47.3 dB at 64x36,
/// 69.0 at 320x180): a texel that blows out the frame falls far below.
pub const HOT_TEXEL_PSNR: f64 = 40.0;
/// An object that must not show: no 8-bit channel off by more than this.
pub const INVISIBLE_MAX_DIFF: u8 = 2;

/// x -> scale * x + offset on a whole scene (roots, cameras, free lights, camera path). Point and spot
/// intensities scale by scale^2 and ranges by scale so the image stays the same; directional lights are
/// unchanged. `scale` > 0. Placements move in f64; the camera path's keys are f32.
pub fn transform_scene(scene: &mut Scene, scale: f64, offset: DVec3) {
    let k = scale as f32;
    for &r in &scene.roots {
        let local = &mut scene.nodes[r].local;
        local.translation = local.translation * scale + offset;
        local.scale *= k;
    }
    for c in &mut scene.cameras {
        *c = transform_camera(c, scale, offset);
    }
    let moved = |p: Vec3| (p.as_dvec3() * scale + offset).as_vec3();
    for key in &mut scene.camera_path {
        key.position = moved(key.position);
        key.target = moved(key.target);
    }
    for l in &mut scene.lights {
        if l.kind == LightKind::Directional {
            continue;
        }
        if l.node.is_none() {
            l.position = l.position * scale + offset;
        }
        l.intensity *= k * k;
        l.range = l.range.map(|r| r * k);
    }
    scene.update_world();
}

/// The camera under x -> scale * x + offset: moved, orientation and field
/// of view kept, near plane scaled.
pub fn transform_camera(c: &Camera, scale: f64, offset: DVec3) -> Camera {
    let mut out = c.clone();
    let p = c.world.w_axis.truncate() * scale + offset;
    out.world.w_axis = p.extend(1.0);
    out.znear = c.znear * scale as f32;
    out
}

/// Adds a one-primitive object as a new root node; returns its object id.
fn add_object(scene: &mut Scene, name: &str, mesh: Mesh, material: Material, local: Transform) -> usize {
    let m = scene.materials.len();
    let casts_shadows = material.casts_shadows;
    scene.materials.push(material);
    let object = scene.objects.len();
    let props = crate::scene::ObjectProps { casts_shadows, ..Default::default() };
    scene.objects.push(Object { name: name.into(), props });
    let mut mesh = mesh;
    mesh.primitives.iter_mut().for_each(|p| p.material = m);
    let node = scene.nodes.len();
    scene.nodes.push(Node {
        name: name.into(),
        local,
        mesh: Some(scene.meshes.len()),
        object: Some(object),
        ..Default::default()
    });
    scene.meshes.push(mesh);
    scene.roots.push(node);
    scene.update_world();
    object
}

fn one(name: &str, p: Primitive) -> Mesh {
    Mesh { name: name.into(), primitives: vec![p] }
}

fn material(name: &str, base: [f32; 3], metallic: f32, roughness: f32) -> Material {
    Material {
        name: name.into(),
        base_color: [base[0], base[1], base[2], 1.0],
        metallic,
        roughness,
        ..Default::default()
    }
}

fn glass(ior: f32) -> Material {
    Material { transmission: 1.0, ior, ..material(&format!("glass ior {ior}"), [1.0; 3], 0.0, 0.0) }
}

/// Materials that can be glossy (render/shading.rs) made rough past GLOSSY_ROUGHNESS, their roughness
/// textures dropped: the image then has no glossy lobe a glass sphere could hide.
/// Also the unshadowed SH ambient (unless the command line names one): the traced ambient, like the
/// glossy lobes, is traced at primary hits only, so a surface seen through glass keeps the SH ambient.
fn rough_glossy(s: &mut Scene) {
    use crate::render::shading::{GLOSSY_ROUGHNESS, MIRROR_ROUGHNESS};
    s.environment.ambient = Some("sh".into());
    for m in &mut s.materials {
        let (low, high) = m.roughness_range();
        if high > MIRROR_ROUGHNESS && low <= GLOSSY_ROUGHNESS {
            m.metallic_roughness_texture = None;
            m.roughness = m.roughness.max(GLOSSY_ROUGHNESS + 0.1);
        }
    }
}

fn mirror(name: &str) -> Material {
    Material { double_sided: true, ..material(name, [1.0; 3], 1.0, 0.0) }
}

/// Where added objects go: the camera's frame and a distance scale.
struct View {
    pos: Vec3,
    f: Vec3,
    u: Vec3,
    r: Vec3,
    rot: Quat,
    /// Distance to the scene's bounds centre (1 without bounds).
    d: f32,
    /// A point in view, halfway to the centre, and a radius that fills
    /// about a third of the frame's half height there.
    spot: Vec3,
    radius: f32,
}

impl View {
    fn of(scene: &Scene, cam: &Camera) -> View {
        let (_, rot, pos) = cam.world.as_mat4().to_scale_rotation_translation();
        let d = if scene.bounds.is_empty() { 1.0 } else { scene.bounds.center().distance(pos).max(1e-3) };
        let f = cam.forward();
        let u = (rot * Vec3::Y).normalize();
        let r = f.cross(u).normalize();
        let spot = pos + f * (0.5 * d);
        let radius = 0.5 * d * (0.5 * cam.yfov).tan() * 0.35;
        View { pos, f, u, r, rot, d, spot, radius }
    }
}

/// A plane (faces +Y) turned to face `normal`, centred at `at`.
fn facing(at: Vec3, normal: Vec3) -> Transform {
    Transform {
        translation: at.as_dvec3(),
        rotation: Quat::from_rotation_arc(Vec3::Y, normal.normalize()),
        ..Default::default()
    }
}

fn at(p: Vec3) -> Transform {
    Transform { translation: p.as_dvec3(), ..Default::default() }
}

fn case(name: &'static str, about: String, scene: Scene, camera: Camera, against: Against) -> Case {
    Case { name, about, scene, camera, depth: None, against, checks: Vec::new() }
}

/// The cases named in `names` (all when empty) plus the canonicals they
/// are compared with, in report order. `dir` receives the OBJ and HDR files.
pub fn build(base: &Scene, cam: &Camera, names: &[String], dir: &Path) -> Result<Vec<Case>> {
    for n in names {
        if !CASE_NAMES.contains(&n.as_str()) {
            anyhow::bail!("unknown stability case '{n}' (cases: {})", CASE_NAMES.join(", "));
        }
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut wanted: Vec<&str> =
        if names.is_empty() { CASE_NAMES.to_vec() } else { names.iter().map(String::as_str).collect() };
    // Canonicals of the wanted cases.
    let canonical = |n: &str| match n {
        "env-texel-1e5" => Some("env-map"),
        "emissive-1e6" => Some("emissive-65504"),
        "tiny-triangles" | "zero-area-triangles" => Some("obj-panel"),
        n if n.starts_with("ior-") => Some("origin-rough"),
        "origin" | "origin-rough" | "env-map" | "emissive-65504" | "obj-panel" => None,
        _ => Some("origin"),
    };
    let extra: Vec<&str> = wanted.iter().filter_map(|n| canonical(n)).collect();
    wanted.extend(extra);
    let mut out = Vec::new();
    for &name in CASE_NAMES.iter().filter(|n| wanted.contains(n)) {
        out.push(make(name, base, cam, dir).with_context(|| format!("building stability case {name}"))?);
    }
    Ok(out)
}

fn make(name: &'static str, base: &Scene, cam: &Camera, dir: &Path) -> Result<Case> {
    let v = View::of(base, cam);
    let mut s = base.clone();
    let origin = Against::Case("origin");
    let psnr = |c: Case, db: f64| Case { checks: vec![Check::PsnrAtLeast(db)], ..c };
    let c = match name {
        "origin" => {
            let c = case(
                name,
                "the scene as loaded (canonical of the moved and scaled cases)".into(),
                s,
                cam.clone(),
                Against::Rt,
            );
            psnr(c, MODE_PSNR)
        }
        n if n.starts_with("translate-") => {
            let dist: f64 = n["translate-".len()..].parse().context("translation")?;
            let offset = DVec3::splat(dist);
            transform_scene(&mut s, 1.0, offset);
            let about = format!("moved by ({dist:e}, {dist:e}, {dist:e}): camera and lights with it");
            psnr(case(name, about, s, transform_camera(cam, 1.0, offset), origin), INVARIANT_PSNR)
        }
        n if n.starts_with("scale-") => {
            let k64: f64 = n["scale-".len()..].parse().context("scale")?;
            transform_scene(&mut s, k64, DVec3::ZERO);
            let about = format!(
                "scaled x{k64:e} about the origin: camera, lights, near plane with it, point/spot intensity x{:.0e}",
                k64 * k64
            );
            psnr(case(name, about, s, transform_camera(cam, k64, DVec3::ZERO), origin), INVARIANT_PSNR)
        }
        "grazing-mirror" => {
            // The central ray meets the plane at 0.5 degrees, at the
            // distance of the scene's centre.
            let a = 0.5f32.to_radians();
            let n = (v.u * a.cos() - v.f * a.sin()).normalize();
            let hit = v.pos + v.f * v.d;
            let plane = primitives::plane(4.0 * v.d, 4.0 * v.d);
            add_object(
                &mut s,
                "grazing mirror",
                one("grazing mirror", plane),
                mirror("mirror"),
                facing(hit, n),
            );
            let about = "a mirror plane (roughness 0, metallic 1) the central camera ray meets at 0.5° at the distance of the scene centre".into();
            let mut c = case(name, about, s, cam.clone(), Against::Rt);
            c.checks = vec![Check::PsnrAtLeast(MODE_PSNR), Check::BlackNotAbove("origin", 0.5)];
            c
        }
        "origin-rough" => {
            rough_glossy(&mut s);
            let about = "the scene with its glossy materials made rough and the SH ambient (canonical of the \
                         glass spheres: glossy lobes and the traced ambient are traced from primary hits only, \
                         so a surface seen through glass keeps the split sum and the SH ambient)";
            psnr(case(name, about.into(), s, cam.clone(), Against::Rt), MODE_PSNR)
        }
        n if n.starts_with("ior-") => {
            let ior: f32 = n["ior-".len()..].parse().context("ior")?;
            rough_glossy(&mut s);
            let sphere = one("sphere", primitives::uv_sphere(v.radius, 64, 32));
            add_object(&mut s, "glass sphere", sphere, glass(ior), at(v.spot));
            let about = format!("a glass sphere (transmission 1, roughness 0) of IOR {ior} in view");
            let mut c = case(name, about, s, cam.clone(), Against::Case("origin-rough"));
            c.checks = match n {
                "ior-1.0" => vec![Check::MaxLdrDiff(INVISIBLE_MAX_DIFF)],
                "ior-1.0001" => vec![Check::PsnrAtLeast(NEAR_INVISIBLE_PSNR)],
                _ => Vec::new(),
            };
            c
        }
        "tir-slab" => {
            // A box's faces meet at right angles: a ray entering one face
            // meets an adjacent one beyond the critical angle (41.8° at 1.5).
            let local = Transform {
                translation: v.spot.as_dvec3(),
                rotation: v.rot
                    * Quat::from_euler(EulerRot::XYZ, 35f32.to_radians(), 40f32.to_radians(), 0.0),
                scale: Vec3::new(2.4, 0.8, 2.4) * v.radius,
            };
            add_object(&mut s, "glass slab", one("slab", primitives::cube(1.0)), glass(1.5), local);
            let about = "a tilted glass slab (IOR 1.5): total internal reflection at its side faces".into();
            psnr(case(name, about, s, cam.clone(), Against::Rt), MODE_PSNR)
        }
        "facing-mirrors" => {
            // Close around the camera and wide enough that rays at the
            // frame's corners stay between them for 64 bounces; they cast
            // no shadow, so the scene's lights reach the ball.
            let a = 0.05 * v.d;
            let mut m = mirror("facing mirror");
            m.base_color = [0.95, 0.95, 0.95, 1.0];
            m.casts_shadows = false;
            for (label, sign) in [("front mirror", 1.0f32), ("back mirror", -1.0)] {
                let plane = primitives::plane(130.0 * a, 130.0 * a);
                add_object(
                    &mut s,
                    label,
                    one(label, plane),
                    m.clone(),
                    facing(v.pos + v.f * a * sign, -v.f * sign),
                );
            }
            let ball = primitives::uv_sphere(0.1 * a, 64, 32);
            let p = v.pos + v.f * 0.6 * a + v.u * 0.05 * a + v.r * 0.08 * a;
            add_object(&mut s, "ball", one("ball", ball), material("ball", [0.8, 0.2, 0.1], 0.0, 0.7), at(p));
            let about =
                "two facing mirrors (0.95) around the camera with a ball between, max depth 64, min weight 0"
                    .into();
            let mut c = psnr(case(name, about, s, cam.clone(), Against::Rt), MODE_PSNR);
            c.depth = Some((64, 0.0));
            c
        }
        "env-map" | "env-texel-1e5" => {
            let hot = name == "env-texel-1e5";
            let path = dir.join(if hot { "env_texel_1e5.hdr" } else { "env_map.hdr" });
            write_env(&s, hot, &path)?;
            s.environment.map = Some(crate::scene::scene_file::load_hdr(&path)?);
            s.environment.map_path = Some(path.clone());
            let about = if hot {
                format!(
                    "{}: the scene's environment with one texel of 1e5 in its top row (a pole: its solid \
                     angle is the map's smallest, so it adds ~1e5 x 7.4e-8 to the mean the ambient term \
                     uses; it is uploaded as 32-bit float, above half's range)",
                    path.display()
                )
            } else {
                format!("{}: the scene's environment as a 512x256 map (canonical)", path.display())
            };
            if hot {
                let mut c = case(name, about, s, cam.clone(), Against::Case("env-map"));
                c.checks = vec![Check::PsnrAtLeast(HOT_TEXEL_PSNR), Check::WhiteNotAbove("env-map", 0.5)];
                c
            } else {
                psnr(case(name, about, s, cam.clone(), Against::Rt), MODE_PSNR)
            }
        }
        "emissive-65504" | "emissive-1e6" => {
            let e = if name == "emissive-1e6" { 1e6 } else { 65504.0 };
            let m = Material { emissive: [e; 3], ..material("emitter", [0.0; 3], 0.0, 1.0) };
            add_object(
                &mut s,
                "emitter",
                one("emitter", primitives::uv_sphere(v.radius, 64, 32)),
                m,
                at(v.spot),
            );
            let about = format!("an emissive sphere of {e:e} in view");
            if e > 65504.0 {
                let mut c = case(name, about, s, cam.clone(), Against::Case("emissive-65504"));
                c.checks = vec![Check::MaxLdrDiff(INVISIBLE_MAX_DIFF)];
                c
            } else {
                psnr(
                    case(name, about + " (the half-float maximum; canonical)", s, cam.clone(), Against::Rt),
                    MODE_PSNR,
                )
            }
        }
        "obj-panel" | "tiny-triangles" | "zero-area-triangles" => {
            let path = dir.join(format!("{}.obj", name.replace('-', "_")));
            std::fs::write(&path, obj_text(name, 1.5 * v.radius))
                .with_context(|| format!("writing {}", path.display()))?;
            let mesh = crate::scene::obj::load_mesh(&path)?;
            // Rough past GLOSSY_ROUGHNESS: a glossy lobe's one sample a frame would turn which of two
            // coincident triangles a ray reports (traversal order) into a visible difference.
            let m = Material { double_sided: true, ..material("panel", [0.8, 0.4, 0.1], 0.0, 0.7) };
            let local = Transform { translation: v.spot.as_dvec3(), rotation: v.rot, ..Default::default() };
            add_object(&mut s, "panel", mesh, m, local);
            let about = match name {
                "obj-panel" => format!("{}: a square panel facing the camera (canonical)", path.display()),
                "tiny-triangles" => {
                    format!("{}: the panel and 24 triangles of edge 1e-6 in front of it", path.display())
                }
                _ => format!("{}: the panel and zero-area triangles sharing its vertices", path.display()),
            };
            if name == "obj-panel" {
                psnr(case(name, about, s, cam.clone(), Against::Rt), MODE_PSNR)
            } else {
                let mut c = case(name, about, s, cam.clone(), Against::Case("obj-panel"));
                c.checks = vec![Check::MaxLdrDiff(INVISIBLE_MAX_DIFF)];
                c
            }
        }
        "near-wall" => {
            let wall = Material { double_sided: true, ..material("wall", [0.6; 3], 0.0, 1.0) };
            add_object(
                &mut s,
                "wall",
                one("wall", primitives::plane(1.0, 1.0)),
                wall,
                facing(v.pos + v.f * 1e-3, -v.f),
            );
            let mut camera = cam.clone();
            // A near plane beyond the wall would clip it away.
            camera.znear = camera.znear.min(1e-4);
            let about = "a wall 1e-3 in front of the camera (near plane 1e-4)".into();
            psnr(case(name, about, s, camera, Against::Rt), MODE_PSNR)
        }
        _ => anyhow::bail!("unknown stability case '{name}'"),
    };
    Ok(c)
}

/// The scene's environment as an equirect map (its own map, or 512x256 of
/// its constant colour), optionally with one texel of 1e5, as .hdr.
fn write_env(scene: &Scene, hot: bool, path: &Path) -> Result<()> {
    let env = &scene.environment;
    let (w, h, mut rgb) = match &env.map {
        Some(m) => (m.width, m.height, m.rgb.clone()),
        None => (512, 256, env.color.to_array().repeat(512 * 256)),
    };
    if hot {
        rgb[..3].copy_from_slice(&[1e5; 3]);
    }
    if let Some(d) = path.parent() {
        std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
    }
    let pixels: Vec<image::Rgb<f32>> = rgb.chunks_exact(3).map(|c| image::Rgb([c[0], c[1], c[2]])).collect();
    let file = std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(file))
        .encode(&pixels, w as usize, h as usize)
        .with_context(|| format!("writing {}", path.display()))
}

/// OBJ text: a square panel of half size `h` in the XY plane facing +Z
/// (the camera), no normals (the reader generates them), plus the case's
/// tiny or zero-area triangles.
fn obj_text(case: &str, h: f32) -> String {
    let mut s = String::from("# written by hybrid-rt report stability\n");
    for (x, y) in [(-h, -h), (h, -h), (h, h), (-h, h)] {
        s += &format!("v {x:.9e} {y:.9e} 0\n");
    }
    let mut faces = vec!["f 1 2 3".to_string(), "f 1 3 4".to_string()];
    match case {
        "tiny-triangles" => {
            // 6 x 4 triangles of edge 1e-6, 0.2 h in front of the panel.
            let e = 1e-6f32;
            let mut n = 4;
            for i in 0..6 {
                for j in 0..4 {
                    let (x, y) = (h * (-0.8 + 0.32 * i as f32), h * (-0.6 + 0.4 * j as f32));
                    for (dx, dy) in [(0.0, 0.0), (e, 0.0), (0.0, e)] {
                        s += &format!("v {:.9e} {:.9e} {:.9e}\n", x + dx, y + dy, 0.2 * h);
                    }
                    faces.push(format!("f {} {} {}", n + 1, n + 2, n + 3));
                    n += 3;
                }
            }
        }
        "zero-area-triangles" => {
            // A repeated corner, three collinear corners (5 is the midpoint
            // of edge 1-2), and a triangle collapsed to one point.
            s += &format!("v 0 {:.9e} 0\n", -h);
            s += &format!("v {:.9e} {:.9e} {:.9e}\n", 0.3 * h, 0.2 * h, 0.2 * h);
            faces.extend(["f 1 1 2", "f 1 5 2", "f 2 3 3", "f 6 6 6"].map(String::from));
        }
        _ => {}
    }
    for f in faces {
        s += &f;
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Light;

    fn light(kind: LightKind, position: Vec3) -> Light {
        Light {
            name: "l".into(),
            kind,
            color: Vec3::ONE,
            intensity: 8.0,
            position: position.as_dvec3(),
            direction: Vec3::new(0.0, -1.0, 0.0),
            range: Some(10.0),
            casts_shadows: true,
            node: None,
        }
    }

    fn scene() -> Scene {
        let mut s = Scene::default();
        add_object(
            &mut s,
            "ball",
            one("ball", primitives::uv_sphere(1.0, 8, 4)),
            material("m", [1.0; 3], 0.0, 1.0),
            at(Vec3::new(1.0, 2.0, 3.0)),
        );
        s.lights.push(light(LightKind::Point, Vec3::new(0.0, 4.0, 0.0)));
        s.lights.push(light(LightKind::Spot { inner_cone: 0.1, outer_cone: 0.5 }, Vec3::new(1.0, 1.0, 1.0)));
        s.lights.push(light(LightKind::Directional, Vec3::ZERO));
        s.cameras.push(Camera::look_at("c", Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, 1.0, 0.05));
        s
    }

    #[test]
    fn translation_moves_instances_cameras_and_lights_only() {
        let mut s = scene();
        let before = s.clone();
        // Offsets an f32 placement would round (spacing 0.0625 at 1e6).
        let t = DVec3::new(1e6 + 0.001, -2e3, 5e2 + 1e-4);
        transform_scene(&mut s, 1.0, t);
        let moved = s.instances[0].world.w_axis.truncate();
        assert_eq!(moved, before.instances[0].world.w_axis.truncate() + t);
        assert_eq!(s.cameras[0].position_f64(), before.cameras[0].position_f64() + t);
        assert_eq!(s.cameras[0].forward(), before.cameras[0].forward());
        assert_eq!(s.cameras[0].znear, 0.05);
        assert_eq!(s.lights[0].position, DVec3::new(0.0, 4.0, 0.0) + t);
        assert_eq!(s.lights[0].intensity, 8.0);
        assert_eq!(s.lights[2].direction, before.lights[2].direction);
        assert_eq!(s.lights[2].position, DVec3::ZERO, "directional lights have no position");
        assert!((s.bounds.center().as_dvec3() - (before.bounds.center().as_dvec3() + t)).length() < 0.1);
    }

    #[test]
    fn scaling_scales_positions_near_plane_and_intensities() {
        let mut s = scene();
        let before = s.clone();
        transform_scene(&mut s, 1e-3, DVec3::ZERO);
        let w = s.instances[0].world;
        assert!((w.w_axis.truncate() - DVec3::new(1e-3, 2e-3, 3e-3)).length() < 1e-9);
        assert!((w.x_axis.length() - 1e-3).abs() < 1e-9, "the instance is scaled too");
        let cam = &s.cameras[0];
        assert!((cam.position_f64() - before.cameras[0].position_f64() * 1e-3).length() < 1e-9);
        assert!((cam.znear / 5e-5 - 1.0).abs() < 1e-6, "{}", cam.znear);
        assert!((cam.forward() - before.cameras[0].forward()).length() < 1e-6);
        for l in &s.lights[..2] {
            assert!((l.intensity - 8e-6).abs() < 1e-12, "{}", l.intensity);
            assert!((l.range.unwrap() - 1e-2).abs() < 1e-9);
        }
        assert!((s.lights[1].position - DVec3::splat(1e-3)).length() < 1e-9);
        assert_eq!((s.lights[2].intensity, s.lights[2].direction), (8.0, before.lights[2].direction));
        // Irradiance from a point light at a scaled distance is unchanged.
        let e = |l: &Light, p: Vec3| l.intensity / l.position.as_vec3().distance_squared(p);
        let p = Vec3::new(0.5, 0.0, 0.5);
        assert!((e(&s.lights[0], p * 1e-3) / e(&before.lights[0], p) - 1.0).abs() < 1e-4);
    }

    #[test]
    fn every_case_builds_and_canonicals_come_along() {
        let dir = std::env::temp_dir().join(format!("hybrid-rt-stability-{}", std::process::id()));
        let s = scene();
        let cases =
            build(&s, &s.cameras[0], &["zero-area-triangles".into(), "ior-1.0".into()], &dir).unwrap();
        let names: Vec<_> = cases.iter().map(|c| c.name).collect();
        assert_eq!(names, ["origin-rough", "ior-1.0", "obj-panel", "zero-area-triangles"]);
        let all = build(&s, &s.cameras[0], &[], &dir).unwrap();
        assert_eq!(all.len(), CASE_NAMES.len());
        assert!(all.iter().all(|c| c.scene.instances.len() >= s.instances.len()));
        assert!(build(&s, &s.cameras[0], &["nope".into()], &dir).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
