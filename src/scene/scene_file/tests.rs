//! Unit tests of scene files: the documented and shipped scenes, every
//! element kind, merged glTF models and the error messages (orbits:
//! orbit_tests.rs).

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

use super::SCENE_ANIMATION;
use crate::scene::animation::find_animation;
use crate::scene::{AlphaMode, LightKind, Scene};

/// Writes `text` as `name` in a scratch directory unique to one test.
pub(super) fn write(test: &str, name: &str, text: &str) -> PathBuf {
    // One fixed folder per test, emptied first: reruns do not pile up temp dirs.
    let dir = std::env::temp_dir().join("hybrid-rt-tests").join(format!("scene-file-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("cannot create a temp dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("cannot write a temp file");
    path
}

pub(super) fn error_of(test: &str, text: &str) -> String {
    match Scene::load(&write(test, "scene.toml", text)) {
        Ok(_) => panic!("scene loaded but should have failed:\n{text}"),
        Err(e) => format!("{e:#}"),
    }
}

pub(super) fn shared(relative: &str) -> String {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/assets")).join(relative);
    assert!(
        path.exists(),
        "missing shared test asset {} (CI keeps ../shared beside the checkout)",
        path.display()
    );
    path.display().to_string()
}

const SMALL: &str = r#"
[environment]
color = [0.2, 0.3, 0.4]
intensity = 2.0
rotation_deg = 90

[[camera]]
name = "main"
position = [0, 1, 5]
target = [0, 1, 0]

[[camera_path]]
time = 0
position = [0, 1, 5]
target = [0, 0, 0]

[[camera_path]]
time = 2.5
position = [5, 1, 0]
target = [0, 0, 0]

[[light]]
type = "directional"
direction = [0, -2, 0]
intensity = 3

[[light]]
type = "spot"
name = "spot"
position = [0, 4, 0]
target = [0, 0, 0]
inner_cone_deg = 10
outer_cone_deg = 20
casts_shadows = false

[[material]]
name = "red"
base_color = [0.8, 0.1, 0.1]
roughness = 0.9

[[material]]
name = "glass"
transmission = 1.0
ior = 1.45
opacity = 0.5
emissive = [1, 0.5, 0]
emissive_strength = 2

[[object]]
name = "floor"
primitive = "plane"
size = [8, 6]

[[object]]
name = "ball"
primitive = "sphere"
radius = 0.25
slices = 8
stacks = 4
translation = [1, 0.25, 0]
material = "glass"
relevance = 2.5
cost = 0.5

[[object]]
name = "box"
primitive = "cube"
size = 0.5
rotation_deg = [90, 90, 0]
scale = [1, 2, 1]
material = "red"
casts_shadows = false
"#;

#[test]
fn small_scene_parses() {
    let scene = Scene::load(&write("small", "scene.toml", SMALL)).unwrap();
    let env = &scene.environment;
    assert_eq!((env.color, env.intensity), (Vec3::new(0.2, 0.3, 0.4), 2.0));
    assert!((env.rotation - std::f32::consts::FRAC_PI_2).abs() < 1e-6);
    assert_eq!(scene.cameras.len(), 1);
    assert_eq!(scene.cameras[0].position(), Vec3::new(0.0, 1.0, 5.0));
    assert_eq!(scene.camera_path.len(), 2);
    assert_eq!(scene.camera_path[1].time, 2.5);

    assert_eq!(scene.lights.len(), 2);
    assert_eq!(scene.lights[0].direction, Vec3::NEG_Y);
    let spot = &scene.lights[1];
    assert_eq!(spot.direction, Vec3::NEG_Y);
    assert!(!spot.casts_shadows);
    let LightKind::Spot { inner_cone, outer_cone } = spot.kind else { panic!("not a spot: {:?}", spot.kind) };
    assert!((inner_cone - 10f32.to_radians()).abs() < 1e-6 && (outer_cone - 20f32.to_radians()).abs() < 1e-6);

    // red, glass, then the default added for the floor.
    let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["red", "glass", "scene default"]);
    let glass = &scene.materials[1];
    assert_eq!((glass.transmission, glass.ior, glass.alpha_mode), (1.0, 1.45, AlphaMode::Blend));
    assert_eq!(glass.base_color, [1.0, 1.0, 1.0, 0.5]);
    assert_eq!(glass.emissive, [2.0, 1.0, 0.0]);
    assert_eq!((scene.materials[2].metallic, scene.materials[2].roughness), (0.0, 0.5));

    assert_eq!(scene.objects.len(), 3);
    assert_eq!(scene.instances.len(), 3);
    let ball = &scene.objects[1];
    assert_eq!((ball.name.as_str(), ball.props.relevance, ball.props.cost), ("ball", 2.5, 0.5));
    assert!(!scene.objects[2].props.casts_shadows);
    let material_of = |object: usize| {
        let inst = scene.instances.iter().find(|i| i.object == object).expect("object has no instance");
        scene.instance_material(inst)
    };
    assert_eq!([material_of(0), material_of(1), material_of(2)], [2, 1, 0]);
    assert_eq!(scene.meshes[0].primitives[0].bounds.max, Vec3::new(4.0, 0.0, 3.0));
}

#[test]
fn rotation_is_x_then_y_about_world_axes() {
    let scene = Scene::load(&write("rotation", "scene.toml", SMALL)).unwrap();
    let world = scene.world_matrices()[2].as_mat4();
    // Box: scale Y by 2, rotate 90 about X (+Y -> +Z) then 90 about Y (+Z -> +X).
    let y = world.transform_vector3(Vec3::Y);
    assert!((y - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-5, "{y}");
}

#[test]
fn gltf_objects_are_merged_as_one_object() {
    let text = format!(
        r#"
[[material]]
name = "chrome"
metallic = 1
roughness = 0.05

[[object]]
name = "plain"
primitive = "cube"

[[object]]
name = "helmet"
gltf = "{}"
translation = [0, 2, 0]
scale = 0.5
material = "chrome"
relevance = 3
"#,
        shared("gltf/DamagedHelmet/glTF/DamagedHelmet.gltf")
    );
    let scene = Scene::load(&write("merge", "scene.toml", &text)).unwrap();
    assert_eq!(scene.objects.len(), 2);
    assert_eq!(scene.objects[1].props.material_override, Some(0));
    assert_eq!(scene.objects[1].props.relevance, 3.0);
    assert_eq!(scene.roots.len(), 2);
    let root = scene.roots[1];
    assert_eq!(scene.nodes[root].name, "helmet");
    assert_eq!(scene.nodes[root].local.translation, glam::DVec3::new(0.0, 2.0, 0.0));
    let helmet: Vec<_> = scene.instances.iter().filter(|i| i.object == 1).collect();
    assert!(!helmet.is_empty());
    for inst in &helmet {
        assert_eq!(scene.instance_material(inst), 0);
        assert!(scene.nodes[inst.node].parent.is_some());
    }
    // Imported materials keep their texture references, re-indexed.
    for m in &scene.materials {
        for t in [m.base_color_texture, m.normal_texture, m.emissive_texture].into_iter().flatten() {
            assert!(t.texture < scene.textures.len());
        }
    }
    assert_eq!(scene.textures.len(), 5);
    let imported = &scene.meshes[helmet[0].mesh].primitives[helmet[0].primitive];
    assert!(scene.materials[imported.material].normal_texture.is_some());
}

#[test]
fn merged_gltf_animations_target_the_merged_nodes() {
    let box_path = shared("gltf/BoxAnimated/glTF/BoxAnimated.gltf");
    let text = format!(
        r#"
[[object]]
name = "plain"
primitive = "cube"

[[object]]
name = "box"
gltf = "{box_path}"
translation = [5, 0, 0]
"#
    );
    let mut scene = Scene::load(&write("animation", "scene.toml", &text)).unwrap();
    let alone = Scene::load(Path::new(&box_path)).unwrap();
    assert_eq!(scene.animations.len(), 1);
    let (merged, original) = (&scene.animations[0], &alone.animations[0]);
    assert_eq!(merged.duration, original.duration);
    assert_eq!(merged.name, format!("box/{}", original.name));
    let root = scene.roots[1];
    for (m, o) in merged.channels.iter().zip(&original.channels) {
        assert_eq!(m.node, o.node + root + 1);
        assert_eq!(scene.nodes[m.node].name, alone.nodes[o.node].name);
    }
    let boxed = |s: &Scene| s.instances.iter().filter(|i| i.object == 1).map(|i| i.world).collect::<Vec<_>>();
    scene.animate(0, 0.0);
    let before = boxed(&scene);
    scene.animate(0, 1.3);
    assert_ne!(before, boxed(&scene));
    let plain: Vec<_> = scene.instances.iter().filter(|i| i.object == 0).map(|i| i.world).collect();
    assert_eq!(plain, vec![glam::DMat4::IDENTITY], "the animation moves only the merged glTF");
}

/// World transform of the node holding `object`'s mesh.
pub(super) fn object_world(scene: &Scene, object: usize) -> Mat4 {
    let node = scene.nodes.iter().position(|n| n.object == Some(object)).expect("object has no node");
    scene.world_matrices()[node].as_mat4()
}

#[test]
fn unknown_key_names_file_and_line() {
    let err = error_of("unknown-key", "[[object]]\nname = \"a\"\nprimitive = \"cube\"\ncolour = 1\n");
    assert!(err.contains("scene.toml") && err.contains("line 4") && err.contains("colour"), "{err}");
}

#[test]
fn unknown_material_is_named() {
    let err =
        error_of("unknown-material", "[[object]]\nname = \"a\"\nprimitive = \"cube\"\nmaterial = \"nope\"\n");
    assert!(
        err.contains("scene.toml:2") && err.contains("object 'a'") && err.contains("unknown material 'nope'"),
        "{err}"
    );
}

/// `[environment] exposure`: a number is a fixed exposure, "auto" auto exposure, none leaves it to
/// `RenderSettings::exposure_for` (auto).
#[test]
fn exposure_is_a_number_or_auto() {
    use crate::scene::SceneExposure;
    for (text, want) in [
        ("exposure = 0.25\n", Some(SceneExposure::Fixed(0.25))),
        ("exposure = 2\n", Some(SceneExposure::Fixed(2.0))),
        ("exposure = \"auto\"\n", Some(SceneExposure::Auto)),
        ("intensity = 1\n", None),
    ] {
        let path = write("exposure", "scene.toml", &format!("[environment]\n{text}"));
        assert_eq!(Scene::load(&path).unwrap().environment.exposure, want, "{text}");
    }
}

#[test]
fn semantic_errors_are_reported() {
    let cases = [
        (
            "[[material]]\nname = \"m\"\n[[material]]\nname = \"m\"\n",
            "scene.toml:4: material 'm' is defined twice",
        ),
        (
            "[[camera_path]]\ntime = 1\nposition = [0,0,0]\ntarget = [0,0,1]\n\
                 [[camera_path]]\ntime = 0.5\nposition = [0,0,0]\ntarget = [0,0,1]\n",
            "scene.toml:6: camera_path times must increase",
        ),
        ("[[object]]\nname = \"x\"\nprimitive = \"cube\"\nobj = \"a.obj\"\n", "exactly one of"),
        ("[[object]]\nname = \"x\"\nobj = \"missing.obj\"\n", "missing.obj"),
        ("[[object]]\nname = \"x\"\ngltf = \"missing.gltf\"\n", "missing.gltf"),
        ("[[light]]\ntype = \"point\"\n", "scene.toml:2: light 'light 0': a point light needs `position`"),
        ("[[light]]\ntype = \"laser\"\n", "laser"),
        ("[[material]]\nname = \"m\"\nroughness = 2\n", "roughness must be within [0, 1]"),
        ("[[material]]\nname = \"m\"\nspecular = 1.5\n", "specular must be within [0, 1]"),
        ("[[material]]\nname = \"m\"\nclearcoat = -0.5\n", "clearcoat must be within [0, 1]"),
        (
            "[[material]]\nname = \"m\"\nclearcoat_roughness = 2\n",
            "clearcoat_roughness must be within [0, 1]",
        ),
        ("[[material]]\nname = \"m\"\nspecular_color = [1, -1, 1]\n", "specular_color components must be"),
        ("[[object]]\nname = \"s\"\nprimitive = \"sphere\"\nsize = 1\n", "a sphere takes `radius`"),
        ("[environment]\ncolor = [1, 1, 1]\nhdr = \"sky.hdr\"\n", "either `color` or `hdr`"),
        ("[environment]\nhdr = \"sky.hdr\"\n", "sky.hdr"),
        ("[environment]\nlayout = \"angular\"\n", "[environment]: `layout` needs an `hdr` map"),
        ("[environment]\nhdr = \"sky.hdr\"\nlayout = \"cube\"\n", "unknown variant `cube`"),
        ("[environment]\nexposure = 0\n", "scene.toml:2: exposure 0: expected a finite number > 0"),
        ("[environment]\nexposure = -2.5\n", "exposure -2.5: expected a finite number > 0"),
        ("[environment]\nexposure = \"bright\"\n", "exposure 'bright': expected a number > 0 or \"auto\""),
        ("[[object]]\nname = \"x\"\nprimitive = \"cube\"\nscale = 0\n", "scale must be finite and non-zero"),
        (
            "[[object]]\nname = \"s\"\nprimitive = \"sphere\"\ncells = 4\n",
            "`cells` and `height` only apply to terrains",
        ),
        (
            "[[object]]\nname = \"t\"\nprimitive = \"terrain\"\ncells = 0\n",
            "1 to 4096 cells per side (got 0 x 0)",
        ),
        ("[[object]]\nname = \"t\"\nprimitive = \"terrain\"\ncells = [8, 5000]\n", "(got 8 x 5000)"),
        (
            "[[object]]\nname = \"t\"\nprimitive = \"terrain\"\nheight = -1\n",
            "height must be finite and >= 0",
        ),
        (
            "[[object]]\nname = \"t\"\nprimitive = \"terrain\"\ncells = 2.5\n",
            "a whole number or an [x, z] array",
        ),
    ];
    for (i, (text, expected)) in cases.iter().enumerate() {
        let err = error_of(&format!("semantic-{i}"), text);
        assert!(err.contains(expected), "expected '{expected}' in: {err}");
    }
}

#[test]
fn hdr_environment_loads() {
    let text = format!(
        "[environment]\nhdr = \"{}\"\nintensity = 0.5\n",
        shared("hdri/polyhaven_1k/potsdamer_platz_1k.hdr")
    );
    let scene = Scene::load(&write("hdr", "scene.toml", &text)).unwrap();
    let map = scene.environment.map.as_ref().expect("no map loaded");
    assert_eq!((map.width, map.height), (1024, 512));
    assert_eq!(map.rgb.len(), 1024 * 512 * 3);
    assert!(map.rgb.iter().all(|v| v.is_finite() && *v >= 0.0));
}

#[test]
fn documented_example_loads() {
    let doc = include_str!("../../../assets/SCENE_FORMAT.md");
    let example = doc.split("```toml\n").nth(1).and_then(|rest| rest.split("```").next());
    let example = example.expect("SCENE_FORMAT.md has no toml example");
    let example = example.replace("../../shared/assets/", &shared(""));
    let scene =
        Scene::load(&write("doc-example", "scene.toml", &example)).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(scene.objects.len(), 3);
    assert_eq!(scene.lights.len(), 2);
    let names: Vec<&str> = scene.animations.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, [SCENE_ANIMATION]);
}

fn shipped(name: &str) -> Scene {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets")).join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e:#}"))
}

#[test]
fn default_scene_is_self_contained() {
    let scene = shipped("default.toml");
    assert!(scene.objects.len() >= 5);
    assert_eq!(scene.lights.iter().filter(|l| l.kind == LightKind::Directional).count(), 1);
    assert_eq!(scene.lights.iter().filter(|l| l.kind == LightKind::Point).count(), 2);
    assert_eq!(scene.lights.iter().filter(|l| matches!(l.kind, LightKind::Spot { .. })).count(), 1);
    assert!(scene.materials.iter().any(|m| m.transmission == 1.0 && m.ior == 1.5));
    assert!(scene.materials.iter().any(|m| m.metallic == 1.0 && m.roughness <= 0.05));
    assert!((3..=4).contains(&scene.camera_path.len()));
    assert!(scene.textures.is_empty());
    // The bundled probe (assets/potsdamer_platz_512.hdr), no other file.
    let map = scene.environment.map.as_ref().expect("the default scene's environment map");
    assert_eq!((map.width, map.height), (512, 256));
    assert!(scene
        .environment
        .map_path
        .as_ref()
        .unwrap()
        .starts_with(concat!(env!("CARGO_MANIFEST_DIR"), "/assets")));
}

#[test]
fn sponza_spheres_scene_loads() {
    let scene = shipped("sponza_spheres.toml");
    assert!(scene.triangle_count() > 100_000);
    // Sponza is one object, plus 4 spheres.
    assert_eq!(scene.objects.len(), 5);
    assert!(scene.camera_path.len() >= 2);
}

/// Closest point to `p` on triangle `abc` (Ericson, Real-Time Collision
/// Detection, 5.1.5).
fn closest_on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let (d3, d4) = (ab.dot(p - b), ac.dot(p - b));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let (d5, d6) = (ab.dot(p - c), ac.dot(p - c));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 >= d3 && d5 >= d6 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[test]
fn sponza_animated_spheres_roll_round_clear_of_the_model() {
    const FLOOR: f32 = 3.98;
    let mut scene = shipped("sponza_animated.toml");
    assert_eq!(scene.objects.len(), 5);
    let index = find_animation(&scene, SCENE_ANIMATION).unwrap();
    let anim = &scene.animations[index];
    assert_eq!((anim.duration, anim.channels.len()), (8.0, 4));

    // Sponza's triangles around the ring, without the floor they roll on.
    let mut triangles = Vec::new();
    for inst in scene.instances.iter().filter(|i| i.object == 0) {
        let p = &scene.meshes[inst.mesh].primitives[inst.primitive];
        for t in p.indices.chunks_exact(3) {
            let world = inst.world.as_mat4();
            let v = [0, 1, 2].map(|k| world.transform_point3(p.vertices[t[k] as usize].position.into()));
            let (lo, hi) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
            let near = lo.cmplt(Vec3::new(3.5, 5.5, 2.0)).all() && hi.cmpgt(Vec3::new(-3.5, 3.9, -3.5)).all();
            if near && hi.y > FLOOR + 0.005 {
                triangles.push(v);
            }
        }
    }
    assert!(triangles.len() > 1000, "only {} triangles near the ring", triangles.len());

    let (mut clearance, mut gap) = (f32::INFINITY, f32::INFINITY);
    for step in 0..64 {
        scene.animate(index, 8.0 * step as f32 / 64.0);
        let centers: Vec<Vec3> = (1..5).map(|o| object_world(&scene, o).w_axis.truncate()).collect();
        for (i, &c) in centers.iter().enumerate() {
            assert!((c.y - 0.6 - FLOOR).abs() < 1e-4, "sphere {i} leaves the floor: {c}");
            for &t in &triangles {
                clearance = clearance.min((closest_on_triangle(c, t) - c).length() - 0.6);
            }
            for &d in &centers[i + 1..] {
                gap = gap.min((d - c).length() - 1.2);
            }
        }
    }
    eprintln!("sponza_animated: spheres stay {clearance:.3} m clear of the model, {gap:.3} m apart");
    assert!(clearance > 0.25, "a sphere comes within {clearance} m of the model");
    assert!(gap > 0.5, "spheres come within {gap} m of each other");
}

#[test]
fn armadillo_scene_loads() {
    let scene = shipped("armadillo_glass.toml");
    assert!(scene.triangle_count() > 86_000);
    let height = scene.bounds.extent().y;
    assert!(height > 1.4 && height < 3.0, "height {height}");
}

#[test]
fn camera_up_rolls_the_view_and_is_validated() {
    let scene = |up: &str| {
        format!("[[camera]]\nposition = [0, 0, 5]\ntarget = [0, 0, 0]\n{up}\n[[object]]\nname = \"box\"\nprimitive = \"cube\"\n")
    };
    let rolled = Scene::load(&write("camera_up", "scene.toml", &scene("up = [1, 0, 0]"))).unwrap();
    // Camera +Y (its up) is world +X; it still looks down world -Z.
    let world = rolled.cameras[0].world.as_mat4();
    assert!((world.y_axis.truncate() - Vec3::X).length() < 1e-6, "{world}");
    assert!((world.z_axis.truncate() - Vec3::Z).length() < 1e-6, "{world}");
    let e = error_of("camera_up_parallel", &scene("up = [0, 0, -2]"));
    assert!(e.contains("camera 'camera 0'") && e.contains("parallel"), "{e}");
    let e = error_of("camera_up_nan", &scene("up = [nan, 1, 0]"));
    assert!(e.contains("up"), "{e}");
}

#[test]
fn volume_attenuation_parses_and_bad_values_name_the_key() {
    let material = |extra: &str| {
        format!(
            "[[material]]\nname = \"tinted\"\ntransmission = 1.0\n{extra}\n\n[[object]]\nname = \"ball\"\n\
             primitive = \"sphere\"\nmaterial = \"tinted\"\n"
        )
    };
    let scene = Scene::load(&write(
        "volume",
        "scene.toml",
        &material("attenuation_color = [0.5, 0.8, 1.0]\nattenuation_distance = 2.0"),
    ))
    .unwrap();
    let m = scene.materials.iter().find(|m| m.name == "tinted").unwrap();
    let sigma = m.volume_sigma();
    let expected = [0.5f32.ln() / -2.0, 0.8f32.ln() / -2.0, 0.0];
    assert!(sigma.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-6), "{sigma:?}");
    // Without a distance the medium is clear, whatever the colour.
    let clear =
        Scene::load(&write("volume-clear", "scene.toml", &material("attenuation_color = [0.5, 0.5, 0.5]")))
            .unwrap();
    assert_eq!(clear.materials.iter().find(|m| m.name == "tinted").unwrap().volume_sigma(), [0.0; 3]);
    for (extra, needle) in [
        ("attenuation_color = [1.5, 1.0, 1.0]", "attenuation_color"),
        ("attenuation_distance = 0.0", "attenuation_distance"),
        ("attenuation_distance = -1.0", "attenuation_distance"),
    ] {
        let err = error_of("volume-bad", &material(extra));
        assert!(err.contains(needle) && err.contains("tinted"), "{extra}: {err}");
    }
}
