//! CPU-side scene: what every loader (glTF, OBJ, scene file, procedural
//! primitives) produces and what the GPU upload consumes.
//!
//! Geometry is kept per mesh primitive (one future BLAS each). Node transforms
//! stay hierarchical so animation can re-evaluate them; `instances` is the
//! flattened draw/trace list derived from the nodes.

pub mod animation;
pub mod camera;
pub mod env_layout;
pub mod generated;
pub mod gltf_import;
mod hdr_image;
pub mod obj;
pub mod primitives;
pub mod scene_file;
pub mod sh;
pub mod skin;
pub mod tangents;

/// The ambient modes' names (`--ambient`, the scene file's
/// `[environment] ambient`; render::AmbientMode checks it has the same).
pub const AMBIENT_NAMES: [&str; 6] =
    ["traced", "sh", "constant", "prt-unshadowed", "prt-shadowed", "prt-interreflected"];

use std::path::{Path, PathBuf};

use anyhow::Result;
use glam::{DMat4, DQuat, DVec3, Mat4, Quat, Vec3};

pub use camera::Camera;
pub use env_layout::EnvLayout;
pub use hdr_image::HdrImage;

/// One vertex of the single shared vertex buffer. Position first so the
/// acceleration-structure builds can read it in place (stride 48).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    /// xyz: tangent, w: bitangent sign (glTF convention: B = cross(N, T) * w).
    pub tangent: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<Vertex>() == 48);

/// A triangle list with one material: the unit of drawing and of BLAS building.
#[derive(Clone, Debug, Default)]
pub struct Primitive {
    pub vertices: Vec<Vertex>,
    /// Always u32 on the CPU side (u8/u16 glTF indices are widened on import).
    pub indices: Vec<u32>,
    pub material: usize,
    /// Object-space bounds of `vertices` (the bind pose when skinned).
    pub bounds: Aabb,
    /// JOINTS_0 / WEIGHTS_0, when the primitive is skinned.
    pub skin: Option<skin::SkinWeights>,
}

#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub name: String,
    pub primitives: Vec<Primitive>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AlphaMode {
    #[default]
    Opaque,
    Mask,
    Blend,
}

/// Index into `Scene::textures`, the UV set it reads and the transform
/// applied to those UVs (KHR_texture_transform; per reference, as in glTF).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: usize,
    pub tex_coord: u32,
    pub transform: UvTransform,
}

/// An affine map of texture coordinates, uv' = M (u, v, 1), held as M's two
/// rows: KHR_texture_transform's translation x rotation x scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    pub rows: [[f32; 3]; 2],
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform { rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] };

    /// glTF's order: scale first, then a counter-clockwise rotation of the
    /// UVs by `rotation` radians (v points down the image), then the offset.
    pub fn from_gltf(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> UvTransform {
        let (s, c) = rotation.sin_cos();
        UvTransform {
            rows: [[c * scale[0], s * scale[1], offset[0]], [-s * scale[0], c * scale[1], offset[1]]],
        }
    }

    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let [a, b] = self.rows;
        [a[0] * uv[0] + a[1] * uv[1] + a[2], b[0] * uv[0] + b[1] * uv[1] + b[2]]
    }
}

impl Default for UvTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// KHR_materials_clearcoat: a dielectric coat (IOR 1.5, its own GGX lobe) over the material, which
/// sees the light the coat's Fresnel lets through. `factor` 0: no coat.
#[derive(Clone, Debug, PartialEq)]
pub struct Clearcoat {
    /// The coat's weight (the texture's R scales it).
    pub factor: f32,
    pub texture: Option<TextureRef>,
    /// Perceptual roughness (the texture's G scales it).
    pub roughness: f32,
    pub roughness_texture: Option<TextureRef>,
    /// The coat's own normal map; without one the coat follows the interpolated vertex normal, not
    /// the base's normal map.
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
}

impl Default for Clearcoat {
    fn default() -> Self {
        Self {
            factor: 0.0,
            texture: None,
            roughness: 0.0,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        }
    }
}

/// glTF metallic-roughness material with the extensions the renderer reads.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub base_color: [f32; 4],
    pub base_color_texture: Option<TextureRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// Metal in B, roughness in G (glTF packing).
    pub metallic_roughness_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    pub occlusion_texture: Option<TextureRef>,
    pub occlusion_strength: f32,
    /// Linear emissive colour already multiplied by KHR_materials_emissive_strength.
    pub emissive: [f32; 3],
    pub emissive_texture: Option<TextureRef>,
    pub alpha_mode: AlphaMode,
    pub alpha_cutoff: f32,
    pub double_sided: bool,
    /// KHR_materials_transmission factor (0 = opaque dielectric/metal).
    pub transmission: f32,
    pub transmission_texture: Option<TextureRef>,
    /// KHR_materials_ior (glTF default 1.5).
    pub ior: f32,
    /// KHR_materials_specular: the dielectric reflection's strength (the
    /// texture's A scales it) and its F0 colour, multiplying the IOR's F0
    /// (the texture's RGB, sRGB, scales it). 1 and white: the IOR alone.
    pub specular: f32,
    pub specular_texture: Option<TextureRef>,
    pub specular_color: [f32; 3],
    pub specular_color_texture: Option<TextureRef>,
    /// KHR_materials_clearcoat: a smooth dielectric layer (IOR 1.5) over the material.
    pub clearcoat: Clearcoat,
    /// KHR_materials_volume: the colour white light turns after travelling
    /// `attenuation_distance` (world units; infinite: a clear medium)
    /// inside the closed mesh (Beer-Lambert along the refracted paths).
    pub attenuation_color: [f32; 3],
    pub attenuation_distance: f32,
    /// Whether geometry with this material occludes light (scene-file flag).
    pub casts_shadows: bool,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: [1.0; 4],
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive: [0.0; 3],
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
            transmission: 0.0,
            transmission_texture: None,
            ior: 1.5,
            specular: 1.0,
            specular_texture: None,
            specular_color: [1.0; 3],
            specular_color_texture: None,
            clearcoat: Clearcoat::default(),
            attenuation_color: [1.0; 3],
            attenuation_distance: f32::INFINITY,
            casts_shadows: true,
        }
    }
}

impl Material {
    /// The roughness its pixels can have: the factor, or with a metallic-roughness texture anything from 0
    /// up to it (the texture's G scales the factor).
    pub fn roughness_range(&self) -> (f32, f32) {
        match self.metallic_roughness_texture {
            Some(_) => (0.0, self.roughness),
            None => (self.roughness, self.roughness),
        }
    }

    /// The roughness a coat's pixels can have, as [`Material::roughness_range`] (None: no coat).
    pub fn coat_roughness_range(&self) -> Option<(f32, f32)> {
        let c = &self.clearcoat;
        (c.factor > 0.0).then_some(match c.roughness_texture {
            Some(_) => (0.0, c.roughness),
            None => (c.roughness, c.roughness),
        })
    }

    /// The medium's attenuation coefficient per world unit, per channel:
    /// -ln(colour) / distance (0 for a clear medium; a black channel is
    /// capped at e^-20 per distance).
    pub fn volume_sigma(&self) -> [f32; 3] {
        if !self.attenuation_distance.is_finite() {
            return [0.0; 3];
        }
        self.attenuation_color.map(|c| -c.max(2e-9).ln() / self.attenuation_distance)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    Linear,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SamplerDesc {
    pub mag_filter: Filter,
    pub min_filter: Filter,
    pub mipmaps: bool,
    pub wrap_u: Wrap,
    pub wrap_v: Wrap,
}

impl Default for SamplerDesc {
    fn default() -> Self {
        Self {
            mag_filter: Filter::Linear,
            min_filter: Filter::Linear,
            mipmaps: true,
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
        }
    }
}

/// A decoded texture, RGBA8. `srgb` follows the glTF spec for the slot that
/// uses it (base colour and emissive are sRGB, the rest linear); an image used
/// both ways appears twice.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
    pub srgb: bool,
    pub sampler: SamplerDesc,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Illuminance in lux along `direction`.
    Directional,
    /// Luminous intensity in candela.
    Point,
    /// Candela, with cone angles in radians (glTF KHR_lights_punctual).
    Spot { inner_cone: f32, outer_cone: f32 },
}

/// A punctual light in world space.
#[derive(Clone, Debug)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    /// Linear RGB colour (not multiplied by intensity).
    pub color: Vec3,
    pub intensity: f32,
    /// World position, f64 like every placement (see [`Transform`]).
    pub position: DVec3,
    /// Direction the light travels (unit length), for directional and spot.
    pub direction: Vec3,
    /// KHR_lights_punctual range; None = infinite.
    pub range: Option<f32>,
    pub casts_shadows: bool,
    /// glTF node the light hangs on (animation moves it), if any.
    pub node: Option<usize>,
}

/// Local TRS of a node. Translation is f64, as is every world placement derived from it: in f32 a
/// scene 1e6 from the origin sits on a 0.0625 grid before the render origin (gpu/origin.rs) can
/// subtract anything. Rotation and scale need no more than f32.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub translation: DVec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self { translation: DVec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE }
    }
}

impl Transform {
    pub fn matrix(&self) -> DMat4 {
        DMat4::from_scale_rotation_translation(
            self.scale.as_dvec3(),
            DQuat::from_array(self.rotation.to_array().map(f64::from)),
            self.translation,
        )
    }
}

/// Per-object settings a scene file can set; defaults for glTF content.
#[derive(Clone, Debug)]
pub struct ObjectProps {
    /// Heuristic relevance weight K (later issue).
    pub relevance: f32,
    /// Heuristic cost factor E (later issue).
    pub cost: f32,
    pub casts_shadows: bool,
    /// Replaces every primitive's material for this object.
    pub material_override: Option<usize>,
}

impl Default for ObjectProps {
    fn default() -> Self {
        Self { relevance: 1.0, cost: 1.0, casts_shadows: true, material_override: None }
    }
}

#[derive(Clone, Debug, Default)]
pub struct Node {
    pub name: String,
    pub parent: Option<usize>,
    pub children: Vec<usize>,
    pub local: Transform,
    pub mesh: Option<usize>,
    pub camera: Option<usize>,
    /// Object id (index into `Scene::objects`) this node's mesh belongs to.
    pub object: Option<usize>,
    /// Skin (index into `Scene::skins`) deforming this node's mesh.
    pub skin: Option<usize>,
}

/// A user-visible object: one loaded model or primitive of a scene file, or
/// one glTF mesh node. Heuristic choices are per object.
#[derive(Clone, Debug, Default)]
pub struct Object {
    pub name: String,
    pub props: ObjectProps,
}

/// One mesh primitive placed in the world: one draw, one TLAS instance.
#[derive(Clone, Copy, Debug)]
pub struct Instance {
    pub node: usize,
    pub mesh: usize,
    pub primitive: usize,
    pub object: usize,
    /// Object-to-world, f64 (see [`Transform`]); the GPU gets it relative
    /// to the render origin.
    pub world: DMat4,
    /// For a skinned primitive: its slot among the scene's skinned instances
    /// (stable while the node hierarchy does not change), which owns a
    /// deformed vertex range and an updatable acceleration structure.
    pub skinned: Option<usize>,
}

#[derive(Clone, Debug)]
pub struct Environment {
    /// Constant radiance when there is no map.
    pub color: Vec3,
    pub map: Option<HdrImage>,
    pub map_path: Option<PathBuf>,
    pub intensity: f32,
    /// Rotation about +Y, radians.
    pub rotation: f32,
    /// The scene file's `ambient` (one of [`AMBIENT_NAMES`]), used
    /// when the command line gives no `--ambient`.
    pub ambient: Option<String>,
    /// The scene file's `exposure`, used when the command line gives neither `--exposure` nor
    /// `--auto-exposure` (`RenderSettings::exposure_for`; without one the frame is auto-exposed).
    pub exposure: Option<SceneExposure>,
}

/// How a scene file asks its frames to be exposed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SceneExposure {
    /// A fixed multiplier (finite, > 0).
    Fixed(f32),
    /// Measured from each frame (histogram auto exposure).
    Auto,
}

/// Only finite values are built, so equality is reflexive.
impl Eq for SceneExposure {}

impl Default for Environment {
    fn default() -> Self {
        Self {
            color: Vec3::splat(0.05),
            map: None,
            map_path: None,
            intensity: 1.0,
            rotation: 0.0,
            ambient: None,
            exposure: None,
        }
    }
}

/// Camera-path keyframe for benchmarks (linear interpolation in time).
#[derive(Clone, Copy, Debug)]
pub struct CameraKey {
    pub time: f32,
    pub position: Vec3,
    pub target: Vec3,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }
    /// Bounds of the eight corners after an affine transform.
    pub fn transformed(&self, m: &Mat4) -> Aabb {
        self.corners_mapped(|c| m.transform_point3(c))
    }

    /// [`Aabb::transformed`] by an f64 placement (corners transformed in
    /// f64, bounds kept in f32).
    pub fn transformed_f64(&self, m: &DMat4) -> Aabb {
        self.corners_mapped(|c| m.transform_point3(c.as_dvec3()).as_vec3())
    }

    fn corners_mapped(&self, f: impl Fn(Vec3) -> Vec3) -> Aabb {
        let mut out = Aabb::EMPTY;
        if self.is_empty() {
            return out;
        }
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            out.grow(f(c));
        }
        out
    }
}

#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// File the scene came from (for messages).
    pub source: PathBuf,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub nodes: Vec<Node>,
    pub roots: Vec<usize>,
    pub objects: Vec<Object>,
    pub lights: Vec<Light>,
    pub cameras: Vec<Camera>,
    pub environment: Environment,
    pub camera_path: Vec<CameraKey>,
    /// Flattened instances, rebuilt by `update_world`.
    pub instances: Vec<Instance>,
    /// World-space bounds of all instances, rebuilt by `update_world`.
    pub bounds: Aabb,
    /// glTF node animations (see [`Scene::animate`]).
    pub animations: Vec<animation::Animation>,
    /// glTF skins, referenced by `Node::skin`.
    pub skins: Vec<skin::Skin>,
}

impl Scene {
    /// Loads a glTF/GLB, an OBJ or a TOML scene file, chosen by extension.
    /// Fills in a default light and camera when the content has none.
    pub fn load(path: &Path) -> Result<Scene> {
        crate::progress::stage(format!("reading {}", path.display()));
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        let mut scene = match ext.as_str() {
            "gltf" | "glb" => gltf_import::load(path)?,
            "obj" => obj::load_scene(path)?,
            "toml" => scene_file::load(path)?,
            _ => anyhow::bail!(
                "{}: unsupported scene format '{}' (expected .gltf, .glb, .obj or .toml)",
                path.display(),
                ext
            ),
        };
        scene.source = path.to_path_buf();
        scene.finish();
        Ok(scene)
    }

    /// Recomputes world transforms, instances and bounds, then adds the
    /// defaults a scene without lights or cameras needs.
    pub fn finish(&mut self) {
        self.update_world();
        camera::add_defaults(self);
    }

    /// World matrices for every node (parents before children not assumed).
    /// Iterative, so a 100,000-level chain does not overflow the stack; a
    /// cycle (which the loaders reject) is cut where it closes.
    pub fn world_matrices(&self) -> Vec<DMat4> {
        let mut world: Vec<Option<DMat4>> = vec![None; self.nodes.len()];
        let mut path = Vec::new();
        for i in 0..self.nodes.len() {
            // Climb to the first resolved ancestor (or a root), then resolve
            // the chain top-down.
            let mut at = Some(i);
            while let Some(n) = at.filter(|&n| world[n].is_none() && path.len() <= self.nodes.len()) {
                path.push(n);
                at = self.nodes[n].parent.filter(|&p| p < self.nodes.len());
            }
            let mut parent = at.and_then(|p| world[p]).unwrap_or(DMat4::IDENTITY);
            while let Some(n) = path.pop() {
                parent *= self.nodes[n].local.matrix();
                world[n] = Some(parent);
            }
        }
        world.into_iter().map(|m| m.unwrap_or(DMat4::IDENTITY)).collect()
    }

    /// Rebuilds `instances` and `bounds` and places node-attached lights (position = world * origin,
    /// direction = normalized world * -Z, per KHR_lights_punctual). Node-attached cameras are not updated.
    pub fn update_world(&mut self) {
        let world = self.world_matrices();
        for light in &mut self.lights {
            let Some(m) = light.node.and_then(|n| world.get(n)) else { continue };
            light.position = m.transform_point3(DVec3::ZERO);
            light.direction = m.transform_vector3(DVec3::NEG_Z).as_vec3().normalize_or(light.direction);
        }
        self.instances.clear();
        self.bounds = Aabb::EMPTY;
        let mut skinned_slots = 0;
        for (n, node) in self.nodes.iter().enumerate() {
            let Some(mesh) = node.mesh else { continue };
            let object = node.object.unwrap_or(0);
            for (p, prim) in self.meshes[mesh].primitives.iter().enumerate() {
                if prim.indices.is_empty() {
                    continue;
                }
                let skinned = (node.skin.is_some() && prim.skin.is_some()).then(|| {
                    skinned_slots += 1;
                    skinned_slots - 1
                });
                self.instances.push(Instance {
                    node: n,
                    mesh,
                    primitive: p,
                    object,
                    world: world[n],
                    skinned,
                });
                // Skinned bounds are the bind pose's: good enough for framing
                // a camera, never used for culling or tracing.
                self.bounds = self.bounds.union(&prim.bounds.transformed_f64(&world[n]));
            }
        }
    }

    /// Per mesh, per primitive: whether some rigid (not skinned) instance
    /// draws it, i.e. whether it needs a static acceleration structure.
    pub fn rigidly_instanced(&self) -> Vec<Vec<bool>> {
        let mut used: Vec<Vec<bool>> = self.meshes.iter().map(|m| vec![false; m.primitives.len()]).collect();
        for i in self.instances.iter().filter(|i| i.skinned.is_none()) {
            used[i.mesh][i.primitive] = true;
        }
        used
    }

    pub fn triangle_count(&self) -> usize {
        self.instances.iter().map(|i| self.meshes[i.mesh].primitives[i.primitive].indices.len() / 3).sum()
    }

    /// Effective material of an instance (object override wins).
    pub fn instance_material(&self, inst: &Instance) -> usize {
        self.objects
            .get(inst.object)
            .and_then(|o| o.props.material_override)
            .unwrap_or(self.meshes[inst.mesh].primitives[inst.primitive].material)
    }
}
