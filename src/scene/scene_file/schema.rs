//! The scene file's structure as serde reads it from TOML: one type per
//! table, unknown keys rejected, spans kept where errors name a line.

use serde::Deserialize;
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) environment: Option<EnvironmentDef>,
    #[serde(default)]
    pub(super) camera: Vec<CameraDef>,
    #[serde(default)]
    pub(super) camera_path: Vec<CameraKeyDef>,
    #[serde(default)]
    pub(super) light: Vec<LightDef>,
    #[serde(default)]
    pub(super) material: Vec<MaterialDef>,
    #[serde(default)]
    pub(super) object: Vec<ObjectDef>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EnvironmentDef {
    pub(super) color: Option<[f32; 3]>,
    pub(super) hdr: Option<Spanned<String>>,
    pub(super) intensity: Option<f32>,
    pub(super) rotation_deg: Option<f32>,
    /// "equirect" (default) or "angular" (Debevec's light probe).
    pub(super) layout: Option<crate::scene::EnvLayout>,
    /// The diffuse ambient mode (`--ambient`'s names), unless the command
    /// line sets one.
    pub(super) ambient: Option<Spanned<String>>,
    /// A fixed exposure (a number) or "auto", unless the command line sets one.
    pub(super) exposure: Option<Spanned<ExposureDef>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum ExposureDef {
    Fixed(f32),
    Named(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraDef {
    pub(super) name: Option<String>,
    /// Placements are f64, like the scene's (see `Transform`).
    pub(super) position: Spanned<[f64; 3]>,
    pub(super) target: [f64; 3],
    pub(super) up: Option<[f32; 3]>,
    pub(super) yfov_deg: Option<f32>,
    pub(super) znear: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraKeyDef {
    pub(super) time: Spanned<f32>,
    pub(super) position: [f32; 3],
    pub(super) target: [f32; 3],
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "lowercase")]
pub(super) enum LightType {
    Directional,
    Point,
    Spot,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightDef {
    #[serde(rename = "type")]
    pub(super) kind: Spanned<LightType>,
    pub(super) name: Option<String>,
    pub(super) color: Option<[f32; 3]>,
    pub(super) intensity: Option<f32>,
    pub(super) position: Option<[f64; 3]>,
    pub(super) direction: Option<[f32; 3]>,
    /// Alternative to `direction` for spot lights: the point they aim at.
    pub(super) target: Option<[f64; 3]>,
    pub(super) range: Option<f32>,
    pub(super) inner_cone_deg: Option<f32>,
    pub(super) outer_cone_deg: Option<f32>,
    pub(super) casts_shadows: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialDef {
    pub(super) name: Spanned<String>,
    pub(super) base_color: Option<Vec<f32>>,
    pub(super) metallic: Option<f32>,
    pub(super) roughness: Option<f32>,
    pub(super) emissive: Option<[f32; 3]>,
    pub(super) emissive_strength: Option<f32>,
    pub(super) transmission: Option<f32>,
    pub(super) ior: Option<f32>,
    pub(super) specular: Option<f32>,
    pub(super) specular_color: Option<[f32; 3]>,
    pub(super) clearcoat: Option<f32>,
    pub(super) clearcoat_roughness: Option<f32>,
    pub(super) attenuation_color: Option<[f32; 3]>,
    pub(super) attenuation_distance: Option<f32>,
    pub(super) opacity: Option<f32>,
    pub(super) double_sided: Option<bool>,
    pub(super) casts_shadows: Option<bool>,
}

#[derive(Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum PrimitiveKind {
    Plane,
    Cube,
    Sphere,
    Terrain,
}

/// `scale = 2` or `scale = [1, 2, 1]`; `size = 2` or `size = [4, 3]`.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged, expecting = "a number or an [x, y, z] array")]
pub(super) enum Scalar3 {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Deserialize, Clone, Copy)]
#[serde(untagged, expecting = "a number or an [x, z] array")]
pub(super) enum Size {
    Uniform(f32),
    Xz([f32; 2]),
}

/// `cells = 512` or `cells = [1024, 512]` (a terrain's quads along X and Z).
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged, expecting = "a whole number or an [x, z] array of whole numbers")]
pub(super) enum Cells {
    Uniform(u32),
    Xz([u32; 2]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ObjectDef {
    pub(super) name: Spanned<String>,
    pub(super) gltf: Option<String>,
    pub(super) obj: Option<String>,
    pub(super) primitive: Option<PrimitiveKind>,
    pub(super) size: Option<Size>,
    pub(super) radius: Option<f32>,
    pub(super) slices: Option<u32>,
    pub(super) stacks: Option<u32>,
    pub(super) cells: Option<Cells>,
    pub(super) height: Option<f32>,
    pub(super) translation: Option<[f64; 3]>,
    pub(super) rotation_deg: Option<[f32; 3]>,
    pub(super) scale: Option<Scalar3>,
    pub(super) material: Option<Spanned<String>>,
    pub(super) casts_shadows: Option<bool>,
    pub(super) relevance: Option<f32>,
    pub(super) cost: Option<f32>,
    pub(super) orbit: Option<OrbitDef>,
}

/// `orbit = { center = [x, y, z], axis = [0, 1, 0], period = 8 }`: the
/// object turns about the line through `center` along `axis`, one full
/// turn per `period` seconds, starting from where its `translation` puts it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct OrbitDef {
    pub(super) center: Option<[f64; 3]>,
    pub(super) axis: Option<[f32; 3]>,
    pub(super) period: Option<f32>,
}
