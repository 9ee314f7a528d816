//! TOML scene files (see assets/SCENE_FORMAT.md): models, procedural
//! primitives, materials, lights, cameras, a camera path and the environment.
//! Paths inside a scene file are relative to the file's directory.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, ensure, Context, Result};
use glam::{EulerRot, Mat4, Quat, Vec3};
use serde::Deserialize;
use toml::Spanned;

use super::animation::{Animation, AnimationChannel, Channel, Interpolation};
use super::{
    gltf_import, obj, primitives, AlphaMode, Camera, CameraKey, Environment, HdrImage, Light, LightKind,
    Material, Mesh, Node, Object, ObjectProps, Primitive, Scene, Transform,
};

/// Loads a scene file. `Scene::load` calls `finish()` afterwards.
pub fn load(path: &Path) -> Result<Scene> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read scene file", path.display()))?;
    let file: SceneFile = toml::from_str(&text).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut builder = Builder {
        scene: Scene::default(),
        dir,
        file: path,
        text: &text,
        materials: HashMap::new(),
        default_material: None,
        orbits: Vec::new(),
    };
    builder.build(file)?;
    Ok(builder.scene)
}

// ---------------------------------------------------------------------------
// File structure

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    environment: Option<EnvironmentDef>,
    #[serde(default)]
    camera: Vec<CameraDef>,
    #[serde(default)]
    camera_path: Vec<CameraKeyDef>,
    #[serde(default)]
    light: Vec<LightDef>,
    #[serde(default)]
    material: Vec<MaterialDef>,
    #[serde(default)]
    object: Vec<ObjectDef>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentDef {
    color: Option<[f32; 3]>,
    hdr: Option<Spanned<String>>,
    intensity: Option<f32>,
    rotation_deg: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDef {
    name: Option<String>,
    position: Spanned<[f32; 3]>,
    target: [f32; 3],
    yfov_deg: Option<f32>,
    znear: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraKeyDef {
    time: Spanned<f32>,
    position: [f32; 3],
    target: [f32; 3],
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "lowercase")]
enum LightType {
    Directional,
    Point,
    Spot,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightDef {
    #[serde(rename = "type")]
    kind: Spanned<LightType>,
    name: Option<String>,
    color: Option<[f32; 3]>,
    intensity: Option<f32>,
    position: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
    /// Alternative to `direction` for spot lights: the point they aim at.
    target: Option<[f32; 3]>,
    range: Option<f32>,
    inner_cone_deg: Option<f32>,
    outer_cone_deg: Option<f32>,
    casts_shadows: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialDef {
    name: Spanned<String>,
    base_color: Option<Vec<f32>>,
    metallic: Option<f32>,
    roughness: Option<f32>,
    emissive: Option<[f32; 3]>,
    emissive_strength: Option<f32>,
    transmission: Option<f32>,
    ior: Option<f32>,
    opacity: Option<f32>,
    double_sided: Option<bool>,
    casts_shadows: Option<bool>,
}

#[derive(Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum PrimitiveKind {
    Plane,
    Cube,
    Sphere,
}

/// `scale = 2` or `scale = [1, 2, 1]`; `size = 2` or `size = [4, 3]`.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged, expecting = "a number or an [x, y, z] array")]
enum Scalar3 {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Deserialize, Clone, Copy)]
#[serde(untagged, expecting = "a number or an [x, z] array")]
enum Size {
    Uniform(f32),
    Xz([f32; 2]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectDef {
    name: Spanned<String>,
    gltf: Option<String>,
    obj: Option<String>,
    primitive: Option<PrimitiveKind>,
    size: Option<Size>,
    radius: Option<f32>,
    slices: Option<u32>,
    stacks: Option<u32>,
    translation: Option<[f32; 3]>,
    rotation_deg: Option<[f32; 3]>,
    scale: Option<Scalar3>,
    material: Option<Spanned<String>>,
    casts_shadows: Option<bool>,
    relevance: Option<f32>,
    cost: Option<f32>,
    orbit: Option<OrbitDef>,
}

/// `orbit = { center = [x, y, z], axis = [0, 1, 0], period = 8 }`: the
/// object turns about the line through `center` along `axis`, one full
/// turn per `period` seconds, starting from where its `translation` puts it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OrbitDef {
    center: Option<[f32; 3]>,
    axis: Option<[f32; 3]>,
    period: Option<f32>,
}

/// Name of the animation that holds every scene-file orbit. It has no `/`,
/// so it never clashes with a merged glTF animation (named "object/name").
pub const SCENE_ANIMATION: &str = "scene";

/// Orbit keys per turn: 45 degrees apart, so the shortest-path slerp between
/// neighbours is unambiguous, and about a fixed axis it is exact (constant
/// angular speed, the true circle), not an approximation.
const ORBIT_KEYS_PER_TURN: usize = 8;

/// Guards against a tiny period making millions of keys.
const MAX_ORBIT_TURNS: f32 = 1000.0;

/// A validated `orbit`, before its pivot exists.
struct OrbitSpec {
    center: Vec3,
    axis: Vec3,
    period: f32,
}

/// An orbit whose pivot node is in the scene; it becomes one channel of the
/// scene animation once every object (and so the longest period) is known.
struct Orbit {
    pivot: usize,
    axis: Vec3,
    period: f32,
    /// "file:line: object 'name'", for errors found after all objects.
    context: String,
}

// ---------------------------------------------------------------------------
// Building the scene

struct Builder<'a> {
    scene: Scene,
    dir: &'a Path,
    file: &'a Path,
    text: &'a str,
    materials: HashMap<String, usize>,
    default_material: Option<usize>,
    orbits: Vec<Orbit>,
}

impl Builder<'_> {
    /// "file:line" for a byte offset into the scene file.
    fn at(&self, offset: usize) -> String {
        format!("{}:{}", self.file.display(), self.line(offset))
    }

    fn line(&self, offset: usize) -> usize {
        self.text.get(..offset).map_or(0, |t| t.matches('\n').count()) + 1
    }

    fn resolve(&self, relative: &str) -> PathBuf {
        self.dir.join(relative)
    }

    fn build(&mut self, file: SceneFile) -> Result<()> {
        if let Some(env) = file.environment {
            self.scene.environment = self.environment(env)?;
        }
        for m in file.material {
            self.add_material(m)?;
        }
        // Scene-file cameras first: the renderer starts with camera 0.
        for (i, c) in file.camera.into_iter().enumerate() {
            let camera = self.camera(c, i)?;
            self.scene.cameras.push(camera);
        }
        self.scene.camera_path = self.camera_path(file.camera_path)?;
        for (i, l) in file.light.into_iter().enumerate() {
            let light = self.light(l, i)?;
            self.scene.lights.push(light);
        }
        for o in file.object {
            let context = format!("{}: object '{}'", self.at(o.name.span().start), o.name.get_ref());
            self.add_object(o, &context).with_context(|| context.clone())?;
        }
        self.add_orbit_animation()
    }

    /// One animation, [`SCENE_ANIMATION`], with a rotation channel per
    /// orbiting object's pivot. It loops at the longest period; every other
    /// period must fit a whole number of times into it so that each orbit
    /// closes seamlessly at the loop (the animation system loops whole
    /// animations, not single channels).
    fn add_orbit_animation(&mut self) -> Result<()> {
        let Some(duration) = self.orbits.iter().map(|o| o.period).reduce(f32::max) else { return Ok(()) };
        let mut channels = Vec::with_capacity(self.orbits.len());
        for o in &self.orbits {
            let ratio = duration / o.period;
            let turns = ratio.round();
            ensure!(
                turns <= MAX_ORBIT_TURNS,
                "{}: orbit.period {} s makes {turns} turns in the longest orbit period ({duration} s); \
                 at most {MAX_ORBIT_TURNS} are allowed",
                o.context,
                o.period
            );
            ensure!(
                (ratio - turns).abs() <= 1e-3 * turns,
                "{}: orbit.period {} s does not divide the longest orbit period {duration} s: all orbits \
                 share the '{SCENE_ANIMATION}' animation, which loops every {duration} s, so each must make \
                 a whole number of turns in it",
                o.context,
                o.period
            );
            channels.push(orbit_channel(o.pivot, o.axis, turns as usize, duration));
        }
        self.scene.animations.push(Animation::new(SCENE_ANIMATION.into(), channels));
        Ok(())
    }

    fn environment(&self, env: EnvironmentDef) -> Result<Environment> {
        let mut out = Environment::default();
        let context = || format!("{}: [environment]", self.file.display());
        if let (Some(_), Some(hdr)) = (&env.color, &env.hdr) {
            bail!("{}: set either `color` or `hdr`, not both", self.at(hdr.span().start));
        }
        if let Some(c) = env.color {
            out.color = non_negative3(c, "color").with_context(context)?;
        }
        if let Some(hdr) = env.hdr {
            let path = self.resolve(hdr.get_ref());
            out.map = Some(load_hdr(&path).with_context(|| self.at(hdr.span().start))?);
            out.map_path = Some(path);
        }
        out.intensity = non_negative(env.intensity.unwrap_or(1.0), "intensity").with_context(context)?;
        out.rotation =
            finite(env.rotation_deg.unwrap_or(0.0), "rotation_deg").with_context(context)?.to_radians();
        Ok(out)
    }

    fn camera(&self, c: CameraDef, index: usize) -> Result<Camera> {
        let name = c.name.unwrap_or_else(|| format!("camera {index}"));
        let context = || format!("{}: camera '{name}'", self.at(c.position.span().start));
        let position = finite3(*c.position.get_ref(), "position").with_context(context)?;
        let target = finite3(c.target, "target").with_context(context)?;
        ensure!(position != target, "{}: position and target coincide", context());
        let yfov = c.yfov_deg.unwrap_or(60.0);
        ensure!(yfov > 0.0 && yfov < 180.0, "{}: yfov_deg {yfov} is outside (0, 180)", context());
        let znear = c.znear.unwrap_or(0.05);
        ensure!(znear > 0.0 && znear.is_finite(), "{}: znear must be positive", context());
        Ok(Camera::look_at(&name, position, target, yfov.to_radians(), znear))
    }

    fn camera_path(&self, keys: Vec<CameraKeyDef>) -> Result<Vec<CameraKey>> {
        let mut out: Vec<CameraKey> = Vec::with_capacity(keys.len());
        for k in keys {
            let at = self.at(k.time.span().start);
            let time = finite(*k.time.get_ref(), "time").with_context(|| at.clone())?;
            if let Some(prev) = out.last() {
                ensure!(
                    time > prev.time,
                    "{at}: camera_path times must increase (time {time} follows {})",
                    prev.time
                );
            }
            let position = finite3(k.position, "position").with_context(|| at.clone())?;
            let target = finite3(k.target, "target").with_context(|| at.clone())?;
            out.push(CameraKey { time, position, target });
        }
        Ok(out)
    }

    fn light(&self, l: LightDef, index: usize) -> Result<Light> {
        let kind = *l.kind.get_ref();
        let name = l.name.clone().unwrap_or_else(|| format!("light {index}"));
        let at = self.at(l.kind.span().start);
        light_from_def(l, kind, name.clone()).with_context(|| format!("{at}: light '{name}'"))
    }

    fn add_material(&mut self, m: MaterialDef) -> Result<()> {
        let name = m.name.get_ref().clone();
        let at = self.at(m.name.span().start);
        ensure!(!self.materials.contains_key(&name), "{at}: material '{name}' is defined twice");
        let material = material_from_def(m).with_context(|| format!("{at}: material '{name}'"))?;
        self.materials.insert(name, self.scene.materials.len());
        self.scene.materials.push(material);
        Ok(())
    }

    fn lookup_material(&self, name: &Spanned<String>) -> Result<usize> {
        self.materials.get(name.get_ref()).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.materials.keys().map(String::as_str).collect();
            known.sort_unstable();
            anyhow!(
                "unknown material '{}' (line {}; defined: {})",
                name.get_ref(),
                self.line(name.span().start),
                if known.is_empty() { "none".to_string() } else { known.join(", ") }
            )
        })
    }

    /// The white dielectric used by primitives and OBJ models without a
    /// `material`, added on first use.
    fn default_material(&mut self) -> usize {
        *self.default_material.get_or_insert_with(|| {
            let material = Material {
                name: "scene default".into(),
                metallic: 0.0,
                roughness: 0.5,
                ..Default::default()
            };
            self.scene.materials.push(material);
            self.scene.materials.len() - 1
        })
    }

    fn add_object(&mut self, o: ObjectDef, context: &str) -> Result<()> {
        let material = o.material.as_ref().map(|m| self.lookup_material(m)).transpose()?;
        let local = object_transform(&o)?;
        // Checked before any model is loaded: a typo fails fast.
        let orbit = o.orbit.as_ref().map(orbit_from_def).transpose()?;
        let props = ObjectProps {
            relevance: non_negative(o.relevance.unwrap_or(1.0), "relevance")?,
            cost: non_negative(o.cost.unwrap_or(1.0), "cost")?,
            casts_shadows: o.casts_shadows.unwrap_or(true),
            material_override: None,
        };
        let name = o.name.get_ref().clone();
        let object = self.scene.objects.len();
        self.scene.objects.push(Object { name: name.clone(), props });
        let node = match (&o.gltf, &o.obj, o.primitive) {
            (Some(file), None, None) => {
                check_no_shape_parameters(&o, "a glTF model")?;
                let imported = gltf_import::load(&self.resolve(file))?;
                self.scene.objects[object].props.material_override = material;
                merge(&mut self.scene, imported, &name, local, object)
            }
            (None, Some(file), None) => {
                check_no_shape_parameters(&o, "an OBJ model")?;
                let mut mesh = obj::load_mesh(&self.resolve(file))?;
                let material = material.unwrap_or_else(|| self.default_material());
                mesh.primitives.iter_mut().for_each(|p| p.material = material);
                self.add_mesh_node(mesh, &name, local, object)
            }
            (None, None, Some(kind)) => {
                let mut primitive = procedural(&o, kind)?;
                primitive.material = material.unwrap_or_else(|| self.default_material());
                let mesh = Mesh { name: name.clone(), primitives: vec![primitive] };
                self.add_mesh_node(mesh, &name, local, object)
            }
            _ => bail!("needs exactly one of `gltf`, `obj` or `primitive`"),
        };
        if let Some(spec) = orbit {
            let pivot = self.add_pivot(node, spec.center, &name);
            let (axis, period) = (spec.axis, spec.period);
            self.orbits.push(Orbit { pivot, axis, period, context: context.to_string() });
        }
        Ok(())
    }

    /// Adds a root node for `mesh`; returns its index.
    fn add_mesh_node(&mut self, mesh: Mesh, name: &str, local: Transform, object: usize) -> usize {
        let node = self.scene.nodes.len();
        self.scene.nodes.push(Node {
            name: name.to_string(),
            local,
            mesh: Some(self.scene.meshes.len()),
            object: Some(object),
            ..Default::default()
        });
        self.scene.meshes.push(mesh);
        self.scene.roots.push(node);
        node
    }

    /// Hangs the root node `node` under a new pivot at `center` that the
    /// orbit animation turns. The node's transform becomes relative to the
    /// pivot, so with the pivot unrotated (t = 0) the object stays exactly
    /// where its `translation` put it.
    fn add_pivot(&mut self, node: usize, center: Vec3, name: &str) -> usize {
        let pivot = self.scene.nodes.len();
        self.scene.nodes.push(Node {
            name: format!("{name} (orbit pivot)"),
            local: Transform { translation: center, ..Default::default() },
            children: vec![node],
            ..Default::default()
        });
        let child = &mut self.scene.nodes[node];
        child.parent = Some(pivot);
        child.local.translation -= center;
        // The pivot takes the object's place among the roots.
        for r in self.scene.roots.iter_mut().filter(|r| **r == node) {
            *r = pivot;
        }
        pivot
    }
}

fn orbit_from_def(o: &OrbitDef) -> Result<OrbitSpec> {
    let center = finite3(o.center.context("orbit needs `center`")?, "orbit.center")?;
    let axis = unit(o.axis.unwrap_or([0.0, 1.0, 0.0]), "orbit.axis")?;
    let period = o.period.context("orbit needs `period` (seconds per turn)")?;
    ensure!(period > 0.0 && period.is_finite(), "orbit.period must be positive and finite (got {period})");
    Ok(OrbitSpec { center, axis, period })
}

/// LINEAR rotation keys for `turns` full turns about `axis` over `duration`
/// seconds, at constant angular speed; the last key (at `duration`) equals
/// the first, so the loop is seamless.
fn orbit_channel(node: usize, axis: Vec3, turns: usize, duration: f32) -> AnimationChannel {
    let n = ORBIT_KEYS_PER_TURN * turns;
    let times = (0..=n).map(|k| duration * k as f32 / n as f32).collect();
    // The angle within the turn, so rounding does not grow with the turn count.
    let step = std::f32::consts::TAU / ORBIT_KEYS_PER_TURN as f32;
    let rotations =
        (0..=n).map(|k| Quat::from_axis_angle(axis, step * (k % ORBIT_KEYS_PER_TURN) as f32)).collect();
    AnimationChannel {
        node,
        times,
        interpolation: Interpolation::Linear,
        values: Channel::Rotation(rotations),
    }
}

// ---------------------------------------------------------------------------
// Element conversion

fn light_from_def(l: LightDef, kind: LightType, name: String) -> Result<Light> {
    let color = non_negative3(l.color.unwrap_or([1.0; 3]), "color")?;
    let intensity = non_negative(l.intensity.unwrap_or(1.0), "intensity")?;
    let position = l.position.map(|p| finite3(p, "position")).transpose()?;
    let aim = match (l.direction, l.target) {
        (Some(_), Some(_)) => bail!("set either `direction` or `target`, not both"),
        (Some(d), None) => Some(unit(d, "direction")?),
        (None, Some(t)) => {
            let from = position.context("`target` needs a `position`")?;
            Some(unit((finite3(t, "target")? - from).to_array(), "target - position")?)
        }
        (None, None) => None,
    };
    if let Some(r) = l.range {
        ensure!(r > 0.0 && r.is_finite(), "range must be positive");
    }
    let has_cones = l.inner_cone_deg.is_some() || l.outer_cone_deg.is_some();
    ensure!(kind == LightType::Spot || !has_cones, "cone angles only apply to spot lights");
    let (kind, position, direction) = match kind {
        LightType::Directional => {
            ensure!(position.is_none(), "a directional light has no position");
            (LightKind::Directional, Vec3::ZERO, aim.context("a directional light needs `direction`")?)
        }
        LightType::Point => {
            ensure!(aim.is_none(), "a point light has no direction");
            (LightKind::Point, position.context("a point light needs `position`")?, Vec3::NEG_Y)
        }
        LightType::Spot => {
            // KHR_lights_punctual defaults: inner 0, outer 45 degrees.
            let inner = l.inner_cone_deg.unwrap_or(0.0);
            let outer = l.outer_cone_deg.unwrap_or(45.0);
            ensure!(
                (0.0..outer).contains(&inner) && outer <= 90.0,
                "cone angles need 0 <= inner_cone_deg < outer_cone_deg <= 90"
            );
            let kind = LightKind::Spot { inner_cone: inner.to_radians(), outer_cone: outer.to_radians() };
            let position = position.context("a spot light needs `position`")?;
            (kind, position, aim.context("a spot light needs `direction` or `target`")?)
        }
    };
    Ok(Light {
        name,
        kind,
        color,
        intensity,
        position,
        direction,
        range: l.range,
        casts_shadows: l.casts_shadows.unwrap_or(true),
        node: None,
    })
}

fn material_from_def(m: MaterialDef) -> Result<Material> {
    let mut base_color = [1.0; 4];
    if let Some(c) = &m.base_color {
        ensure!(c.len() == 3 || c.len() == 4, "base_color needs 3 or 4 components, got {}", c.len());
        ensure!(m.opacity.is_none() || c.len() == 3, "set the alpha either in base_color or as opacity");
        for (dst, &v) in base_color.iter_mut().zip(c) {
            *dst = non_negative(v, "base_color")?;
        }
    }
    if let Some(o) = m.opacity {
        base_color[3] = o;
    }
    ensure!(base_color[3] <= 1.0, "opacity must be within [0, 1]");
    let emissive = non_negative3(m.emissive.unwrap_or([0.0; 3]), "emissive")?;
    let strength = non_negative(m.emissive_strength.unwrap_or(1.0), "emissive_strength")?;
    let ior = m.ior.unwrap_or(1.5);
    ensure!(ior >= 1.0 && ior.is_finite(), "ior must be at least 1");
    Ok(Material {
        name: m.name.get_ref().clone(),
        base_color,
        metallic: unit_interval(m.metallic.unwrap_or(0.0), "metallic")?,
        roughness: unit_interval(m.roughness.unwrap_or(0.5), "roughness")?,
        emissive: (emissive * strength).to_array(),
        alpha_mode: if base_color[3] < 1.0 { AlphaMode::Blend } else { AlphaMode::Opaque },
        double_sided: m.double_sided.unwrap_or(false),
        transmission: unit_interval(m.transmission.unwrap_or(0.0), "transmission")?,
        ior,
        casts_shadows: m.casts_shadows.unwrap_or(true),
        ..Material::default()
    })
}

/// Translation, then rotation (X, then Y, then Z about the world axes, as
/// Blender's "XYZ Euler"), then scale: the usual TRS.
fn object_transform(o: &ObjectDef) -> Result<Transform> {
    let translation = finite3(o.translation.unwrap_or([0.0; 3]), "translation")?;
    let [x, y, z] =
        finite3(o.rotation_deg.unwrap_or([0.0; 3]), "rotation_deg")?.to_array().map(f32::to_radians);
    let scale = match o.scale.unwrap_or(Scalar3::Uniform(1.0)) {
        Scalar3::Uniform(s) => Vec3::splat(s),
        Scalar3::PerAxis(s) => Vec3::from(s),
    };
    ensure!(scale.is_finite() && scale.cmpne(Vec3::ZERO).all(), "scale must be finite and non-zero");
    Ok(Transform { translation, rotation: Quat::from_euler(EulerRot::ZYX, z, y, x), scale })
}

fn check_no_shape_parameters(o: &ObjectDef, what: &str) -> Result<()> {
    let set = [
        ("size", o.size.is_some()),
        ("radius", o.radius.is_some()),
        ("slices", o.slices.is_some()),
        ("stacks", o.stacks.is_some()),
    ];
    if let Some((key, _)) = set.iter().find(|(_, s)| *s) {
        bail!("`{key}` only applies to primitives; scale {what} with `scale`");
    }
    Ok(())
}

fn procedural(o: &ObjectDef, kind: PrimitiveKind) -> Result<Primitive> {
    let sphere_only = o.radius.is_some() || o.slices.is_some() || o.stacks.is_some();
    ensure!(
        kind == PrimitiveKind::Sphere || !sphere_only,
        "`radius`, `slices` and `stacks` only apply to spheres"
    );
    let positive = |v: f32, what: &str| {
        ensure!(v > 0.0 && v.is_finite(), "{what} must be positive");
        Ok(v)
    };
    Ok(match kind {
        PrimitiveKind::Plane => {
            let [x, z] = match o.size.unwrap_or(Size::Xz([10.0, 10.0])) {
                Size::Uniform(s) => [s, s],
                Size::Xz(xz) => xz,
            };
            primitives::plane(positive(x, "size")?, positive(z, "size")?)
        }
        PrimitiveKind::Cube => match o.size.unwrap_or(Size::Uniform(1.0)) {
            Size::Uniform(s) => primitives::cube(positive(s, "size")?),
            Size::Xz(_) => bail!("a cube's `size` is one number (use `scale` for boxes)"),
        },
        PrimitiveKind::Sphere => {
            ensure!(o.size.is_none(), "a sphere takes `radius`, not `size`");
            let (slices, stacks) = (o.slices.unwrap_or(64), o.stacks.unwrap_or(32));
            ensure!(slices >= 3 && stacks >= 2, "a sphere needs slices >= 3 and stacks >= 2");
            primitives::uv_sphere(positive(o.radius.unwrap_or(0.5), "radius")?, slices, stacks)
        }
    })
}

/// Appends an imported glTF scene under a new root node carrying the
/// object's transform; returns the root. Every mesh node joins the one
/// `object`, so the heuristics treat the model as a single object. The
/// model's animations are renamed "object/animation": two objects loading
/// the same file, and the scene-file animation, stay apart by name.
fn merge(scene: &mut Scene, sub: Scene, name: &str, local: Transform, object: usize) -> usize {
    let (mesh_base, material_base, texture_base) =
        (scene.meshes.len(), scene.materials.len(), scene.textures.len());
    let (camera_base, skin_base) = (scene.cameras.len(), scene.skins.len());
    let root = scene.nodes.len();
    let node_base = root + 1;
    let placement = local.matrix();

    scene.textures.extend(sub.textures);
    scene.materials.extend(sub.materials.into_iter().map(|mut m| {
        for t in [
            &mut m.base_color_texture,
            &mut m.metallic_roughness_texture,
            &mut m.normal_texture,
            &mut m.occlusion_texture,
            &mut m.emissive_texture,
            &mut m.transmission_texture,
        ]
        .into_iter()
        .flatten()
        {
            t.texture += texture_base;
        }
        m
    }));
    scene.meshes.extend(sub.meshes.into_iter().map(|mut mesh| {
        mesh.primitives.iter_mut().for_each(|p| p.material += material_base);
        mesh
    }));
    let children: Vec<usize> = sub.roots.iter().map(|r| r + node_base).collect();
    scene.nodes.push(Node { name: name.to_string(), local, children, ..Default::default() });
    for (i, mut n) in sub.nodes.into_iter().enumerate() {
        n.parent = n.parent.map(|p| p + node_base).or_else(|| sub.roots.contains(&i).then_some(root));
        n.children.iter_mut().for_each(|c| *c += node_base);
        n.mesh = n.mesh.map(|m| m + mesh_base);
        n.camera = n.camera.map(|c| c + camera_base);
        n.skin = n.skin.map(|k| k + skin_base);
        n.object = n.mesh.map(|_| object);
        scene.nodes.push(n);
    }
    scene.roots.push(root);
    scene.cameras.extend(sub.cameras.into_iter().map(|mut c| {
        c.world = placement * c.world;
        c
    }));
    scene.lights.extend(sub.lights.into_iter().map(|l| place_light(l, &placement, node_base)));
    scene.skins.extend(sub.skins.into_iter().map(|mut k| {
        k.joints.iter_mut().for_each(|j| *j += node_base);
        k
    }));
    scene.animations.extend(sub.animations.into_iter().map(|mut a| {
        a.name = format!("{name}/{}", a.name);
        a.channels.iter_mut().for_each(|c| c.node += node_base);
        a
    }));
    root
}

fn place_light(mut l: Light, placement: &Mat4, node_base: usize) -> Light {
    l.position = placement.transform_point3(l.position);
    l.direction = placement.transform_vector3(l.direction).normalize_or(l.direction);
    l.node = l.node.map(|n| n + node_base);
    l
}

/// Equirectangular Radiance HDR; non-finite and negative texels (which would
/// poison importance sampling) become 0.
fn load_hdr(path: &Path) -> Result<HdrImage> {
    let image = image::open(path)
        .with_context(|| format!("cannot load environment map '{}'", path.display()))?
        .into_rgb32f();
    let (width, height) = image.dimensions();
    let mut rgb = image.into_raw();
    let mut bad = 0usize;
    for v in &mut rgb {
        if !v.is_finite() || *v < 0.0 {
            *v = 0.0;
            bad += 1;
        }
    }
    if bad > 0 {
        log::warn!("{}: {bad} non-finite or negative values set to 0", path.display());
    }
    Ok(HdrImage { width, height, rgb })
}

// ---------------------------------------------------------------------------
// Value checks

fn finite(v: f32, what: &str) -> Result<f32> {
    ensure!(v.is_finite(), "{what} must be finite");
    Ok(v)
}

fn finite3(v: [f32; 3], what: &str) -> Result<Vec3> {
    ensure!(v.iter().all(|c| c.is_finite()), "{what} must be finite");
    Ok(Vec3::from(v))
}

fn non_negative(v: f32, what: &str) -> Result<f32> {
    ensure!(v.is_finite() && v >= 0.0, "{what} must be finite and >= 0 (got {v})");
    Ok(v)
}

fn non_negative3(v: [f32; 3], what: &str) -> Result<Vec3> {
    ensure!(v.iter().all(|c| c.is_finite() && *c >= 0.0), "{what} components must be finite and >= 0");
    Ok(Vec3::from(v))
}

fn unit_interval(v: f32, what: &str) -> Result<f32> {
    ensure!((0.0..=1.0).contains(&v), "{what} must be within [0, 1] (got {v})");
    Ok(v)
}

fn unit(v: [f32; 3], what: &str) -> Result<Vec3> {
    finite3(v, what)?.try_normalize().with_context(|| format!("{what} must not be zero"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::animation::find_animation;

    /// Writes `text` as `name` in a scratch directory unique to one test.
    fn write(test: &str, name: &str, text: &str) -> PathBuf {
        // One fixed folder per test, emptied first: reruns do not pile up temp dirs.
        let dir = std::env::temp_dir().join("hybrid-rt-tests").join(format!("scene-file-{test}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("cannot create a temp dir");
        let path = dir.join(name);
        std::fs::write(&path, text).expect("cannot write a temp file");
        path
    }

    fn error_of(test: &str, text: &str) -> String {
        match Scene::load(&write(test, "scene.toml", text)) {
            Ok(_) => panic!("scene loaded but should have failed:\n{text}"),
            Err(e) => format!("{e:#}"),
        }
    }

    fn shared(relative: &str) -> String {
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
        let LightKind::Spot { inner_cone, outer_cone } = spot.kind else {
            panic!("not a spot: {:?}", spot.kind)
        };
        assert!(
            (inner_cone - 10f32.to_radians()).abs() < 1e-6 && (outer_cone - 20f32.to_radians()).abs() < 1e-6
        );

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
        let world = scene.world_matrices()[2];
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
        assert_eq!(scene.nodes[root].local.translation, Vec3::new(0.0, 2.0, 0.0));
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
        let boxed =
            |s: &Scene| s.instances.iter().filter(|i| i.object == 1).map(|i| i.world).collect::<Vec<_>>();
        scene.animate(0, 0.0);
        let before = boxed(&scene);
        scene.animate(0, 1.3);
        assert_ne!(before, boxed(&scene));
        let plain: Vec<_> = scene.instances.iter().filter(|i| i.object == 0).map(|i| i.world).collect();
        assert_eq!(plain, vec![glam::Mat4::IDENTITY], "the animation moves only the merged glTF");
    }

    /// Two orbits: a rotated, scaled cube about +Y (8 s) and a sphere about
    /// an oblique axis (4 s: two turns per loop of the scene animation).
    const ORBITS: &str = r#"
[[object]]
name = "still"
primitive = "plane"

[[object]]
name = "cube"
primitive = "cube"
translation = [3, 1, 0.5]
rotation_deg = [0, 30, 0]
scale = [1, 2, 1]
orbit = { center = [1, 1, 0], period = 8.0 }

[[object]]
name = "ball"
primitive = "sphere"
translation = [0, 2, -2]
orbit = { center = [0.5, 0, -1], axis = [1, 1, 0], period = 4.0 }
"#;

    /// World transform of the node holding `object`'s mesh.
    fn object_world(scene: &Scene, object: usize) -> Mat4 {
        let node = scene.nodes.iter().position(|n| n.object == Some(object)).expect("object has no node");
        scene.world_matrices()[node]
    }

    fn assert_close(got: Vec3, expected: Vec3, what: &str) {
        let error = (got - expected).length();
        assert!(error <= 1e-4 * expected.length().max(1.0), "{what}: {got} vs {expected} (error {error})");
    }

    #[test]
    fn orbits_follow_the_analytic_circle() {
        let mut scene = Scene::load(&write("orbits", "scene.toml", ORBITS)).unwrap();
        assert_eq!(scene.animations.len(), 1);
        let anim = &scene.animations[0];
        assert_eq!((anim.name.as_str(), anim.duration, anim.channels.len()), (SCENE_ANIMATION, 8.0, 2));
        for c in &anim.channels {
            c.check().unwrap();
            assert_eq!(c.interpolation, Interpolation::Linear);
            assert_eq!(scene.nodes[c.node].children.len(), 1, "channels target the pivots");
        }
        assert_eq!(scene.roots.len(), 3);
        let index = find_animation(&scene, SCENE_ANIMATION).unwrap();

        // (object, translation, centre, unit axis, period)
        let orbits = [
            (1, Vec3::new(3.0, 1.0, 0.5), Vec3::new(1.0, 1.0, 0.0), Vec3::Y, 8.0f32),
            (
                2,
                Vec3::new(0.0, 2.0, -2.0),
                Vec3::new(0.5, 0.0, -1.0),
                Vec3::new(1.0, 1.0, 0.0).normalize(),
                4.0,
            ),
        ];
        // Before any animation the scene is posed as the file says.
        let unmoved = Mat4::from_scale_rotation_translation(
            Vec3::new(1.0, 2.0, 1.0),
            Quat::from_rotation_y(30f32.to_radians()),
            orbits[0].1,
        );
        assert!(object_world(&scene, 1).abs_diff_eq(unmoved, 1e-5), "{}", object_world(&scene, 1));
        // As loaded (no animation applied yet).
        let rests = orbits.map(|o| object_world(&scene, o.0));
        for ((object, translation, center, axis, period), rest) in orbits.into_iter().zip(rests) {
            // Quarter periods are keys; 0.3 and 1.55 periods lie between keys
            // (slerp about a fixed axis stays on the circle) and in a later lap.
            for fraction in [0.0f32, 0.25, 0.5, 0.75, 1.0, 0.3, 1.55] {
                let t = fraction * period;
                scene.animate(index, t);
                let turn = Quat::from_axis_angle(axis, std::f32::consts::TAU * fraction);
                let expected = center + turn * (translation - center);
                let world = object_world(&scene, object);
                assert_close(world.w_axis.truncate(), expected, &format!("object {object} at t = {t}"));
                // The object turns with its orbit (like a moon showing one face).
                let about_center =
                    Mat4::from_translation(center) * Mat4::from_quat(turn) * Mat4::from_translation(-center);
                assert!(world.abs_diff_eq(about_center * rest, 1e-4), "object {object} at t = {t}: {world}");
            }
        }
        // The plane without an orbit never moves.
        scene.animate(index, 3.0);
        assert_eq!(object_world(&scene, 0), Mat4::IDENTITY);
    }

    #[test]
    fn orbit_errors_name_file_object_and_key() {
        let object = |orbit: &str| {
            format!("[[object]]\nname = \"ball\"\nprimitive = \"sphere\"\norbit = {{ {orbit} }}\n")
        };
        let cases = [
            ("center = [0, 0, 0], period = 0", "orbit.period must be positive and finite (got 0)"),
            ("center = [0, 0, 0], period = -2", "orbit.period must be positive and finite (got -2)"),
            ("center = [0, 0, 0], period = inf", "orbit.period must be positive and finite (got inf)"),
            ("center = [0, 0, 0], period = nan", "orbit.period must be positive and finite (got NaN)"),
            ("center = [0, 0, 0], axis = [0, 0, 0], period = 1", "orbit.axis must not be zero"),
            ("center = [0, 0, 0], axis = [0, nan, 0], period = 1", "orbit.axis must be finite"),
            ("center = [0, inf, 0], period = 1", "orbit.center must be finite"),
            ("center = [0, 0, 0]", "orbit needs `period`"),
            ("period = 1", "orbit needs `center`"),
        ];
        for (i, (orbit, expected)) in cases.iter().enumerate() {
            let err = error_of(&format!("orbit-{i}"), &object(orbit));
            assert!(
                err.contains("scene.toml:2: object 'ball': ") && err.contains(expected),
                "expected '{expected}' with file, line and object in: {err}"
            );
        }
        // Unknown orbit keys are rejected by the parser, with their line.
        let err = error_of("orbit-unknown", &object("center = [0, 0, 0], period = 1, phase_deg = 90"));
        assert!(err.contains("scene.toml") && err.contains("line 4") && err.contains("phase_deg"), "{err}");
        // Periods that do not divide the longest one cannot share its loop.
        let text = format!(
            "{}[[object]]\nname = \"odd\"\nprimitive = \"cube\"\norbit = {{ center = [0, 0, 0], period = 3 }}\n",
            object("center = [0, 0, 0], period = 8")
        );
        let err = error_of("orbit-periods", &text);
        assert!(
            err.contains(
                "scene.toml:6: object 'odd': orbit.period 3 s does not divide the longest orbit period 8 s"
            ),
            "{err}"
        );
        let text = format!(
            "{}[[object]]\nname = \"fast\"\nprimitive = \"cube\"\norbit = {{ center = [0, 0, 0], period = 1e-3 }}\n",
            object("center = [0, 0, 0], period = 8")
        );
        let err = error_of("orbit-fast", &text);
        assert!(err.contains("object 'fast': orbit.period 0.001 s makes 8000 turns"), "{err}");
    }

    #[test]
    fn orbits_beside_merged_gltf_animations() {
        let box_path = shared("gltf/BoxAnimated/glTF/BoxAnimated.gltf");
        let text = format!(
            r#"
[[object]]
name = "box"
gltf = "{box_path}"
translation = [5, 0, 0]
orbit = {{ center = [0, 0, 0], period = 6 }}

[[object]]
name = "ball"
primitive = "sphere"
translation = [0, 0, 2]
orbit = {{ center = [0, 0, 0], axis = [1, 0, 0], period = 3 }}
"#
        );
        let mut scene = Scene::load(&write("orbit-gltf", "scene.toml", &text)).unwrap();
        let alone = Scene::load(Path::new(&box_path)).unwrap();
        // The glTF's animations keep their indices; the orbits come after.
        let names: Vec<&str> = scene.animations.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, [format!("box/{}", alone.animations[0].name).as_str(), SCENE_ANIMATION]);
        assert_eq!(find_animation(&scene, SCENE_ANIMATION).unwrap(), 1);
        assert_eq!(scene.animations[1].duration, 6.0);
        let positions = |s: &Scene| {
            let world = s.world_matrices();
            s.instances.iter().map(|i| (i.object, world[i.node].w_axis.truncate())).collect::<Vec<_>>()
        };
        let rest = positions(&scene);

        // The box's own animation moves only the box's parts, in place.
        scene.animate(0, 1.3);
        let boxed = positions(&scene);
        assert!(rest.iter().zip(&boxed).any(|(a, b)| a.0 == 0 && a.1 != b.1));
        assert!(rest.iter().zip(&boxed).all(|(a, b)| a.0 == 0 || a == b));

        // Half the box's period: the whole model is across the centre (the
        // merged root at -5), and the ball has made one full turn (period 3).
        scene.animate(1, 3.0);
        let box_root = scene.nodes.iter().position(|n| n.name == "box").unwrap();
        assert_close(
            scene.world_matrices()[box_root].w_axis.truncate(),
            Vec3::new(-5.0, 0.0, 0.0),
            "box root",
        );
        assert_close(object_world(&scene, 1).w_axis.truncate(), Vec3::new(0.0, 0.0, 2.0), "ball");
        // A quarter of the ball's period about +X: +Z turns to -Y.
        scene.animate(1, 0.75);
        assert_close(object_world(&scene, 1).w_axis.truncate(), Vec3::new(0.0, -2.0, 0.0), "ball");
    }

    #[test]
    fn unknown_key_names_file_and_line() {
        let err = error_of("unknown-key", "[[object]]\nname = \"a\"\nprimitive = \"cube\"\ncolour = 1\n");
        assert!(err.contains("scene.toml") && err.contains("line 4") && err.contains("colour"), "{err}");
    }

    #[test]
    fn unknown_material_is_named() {
        let err = error_of(
            "unknown-material",
            "[[object]]\nname = \"a\"\nprimitive = \"cube\"\nmaterial = \"nope\"\n",
        );
        assert!(
            err.contains("scene.toml:2")
                && err.contains("object 'a'")
                && err.contains("unknown material 'nope'"),
            "{err}"
        );
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
            (
                "[[light]]\ntype = \"point\"\n",
                "scene.toml:2: light 'light 0': a point light needs `position`",
            ),
            ("[[light]]\ntype = \"laser\"\n", "laser"),
            ("[[material]]\nname = \"m\"\nroughness = 2\n", "roughness must be within [0, 1]"),
            ("[[object]]\nname = \"s\"\nprimitive = \"sphere\"\nsize = 1\n", "a sphere takes `radius`"),
            ("[environment]\ncolor = [1, 1, 1]\nhdr = \"sky.hdr\"\n", "either `color` or `hdr`"),
            ("[environment]\nhdr = \"sky.hdr\"\n", "sky.hdr"),
            (
                "[[object]]\nname = \"x\"\nprimitive = \"cube\"\nscale = 0\n",
                "scale must be finite and non-zero",
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
        let doc = include_str!("../../assets/SCENE_FORMAT.md");
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
        assert!(scene.textures.is_empty() && scene.environment.map.is_none());
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
                let v =
                    [0, 1, 2].map(|k| inst.world.transform_point3(p.vertices[t[k] as usize].position.into()));
                let (lo, hi) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
                let near =
                    lo.cmplt(Vec3::new(3.5, 5.5, 2.0)).all() && hi.cmpgt(Vec3::new(-3.5, 3.9, -3.5)).all();
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
}
