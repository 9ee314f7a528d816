//! Rust mirrors of `glsl/common/types.glsl` (scalar block layout). The
//! sizes are asserted against the strides in `shared_values.rs`, which the
//! shaders' layout is tested against (tests/render/shared_layout.rs).

use bytemuck::{Pod, Zeroable};

pub use super::shared::{
    ALPHA_BLEND, ALPHA_MASK, ALPHA_OPAQUE, INST_CASTS_SHADOWS, LIGHT_CASTS_SHADOWS, LIGHT_DIRECTIONAL,
    LIGHT_POINT, LIGHT_SPOT, MAT_CASTS_SHADOWS, MAT_DOUBLE_SIDED,
};
use super::shared::{
    INSTANCE_STRIDE, LIGHT_STRIDE, MATERIAL_STRIDE, SH_IRRADIANCE_COEFFS, SH_PRT_MAX_COEFFS, VERTEX_STRIDE,
};

const _: () = assert!(std::mem::size_of::<crate::scene::Vertex>() == VERTEX_STRIDE as usize);

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuMaterial {
    pub base_color: [f32; 4],
    pub emissive: [f32; 3],
    pub metallic: f32,
    pub roughness: f32,
    pub normal_scale: f32,
    pub occlusion_strength: f32,
    pub alpha_cutoff: f32,
    pub transmission: f32,
    pub ior: f32,
    pub alpha_mode: u32,
    pub flags: u32,
    pub tex_base_color: i32,
    pub tex_metallic_roughness: i32,
    pub tex_normal: i32,
    pub tex_occlusion: i32,
    pub tex_emissive: i32,
    pub tex_transmission: i32,
    /// Material::volume_sigma.
    pub volume_sigma: [f32; 3],
    /// KHR_materials_specular: Material::specular and its texture (A), the
    /// F0 colour's texture (RGB); the colour factor is below.
    pub specular: f32,
    pub tex_specular: i32,
    pub tex_specular_color: i32,
    /// Each texture reference's KHR_texture_transform (UvTransform::rows),
    /// in the order of the tex_* indices above.
    pub uv_transforms: [[[f32; 3]; 2]; 8],
    pub specular_color: [f32; 3],
    pub pad: u32,
    /// KHR_materials_clearcoat (scene::Clearcoat): weight (texture R), roughness (texture G), the
    /// coat's normal map; then those three references' transforms.
    pub clearcoat: f32,
    pub clearcoat_roughness: f32,
    pub clearcoat_normal_scale: f32,
    pub tex_clearcoat: i32,
    pub tex_clearcoat_roughness: i32,
    pub tex_clearcoat_normal: i32,
    pub uv_clearcoat: [[[f32; 3]; 2]; 3],
}
const _: () = assert!(std::mem::size_of::<GpuMaterial>() == MATERIAL_STRIDE as usize);

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuInstance {
    pub world: [f32; 16],
    pub normal_matrix: [f32; 16],
    pub material: u32,
    pub first_index: u32,
    pub vertex_offset: u32,
    pub object_id: u32,
    pub index_count: u32,
    pub flags: u32,
    pub pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<GpuInstance>() == INSTANCE_STRIDE as usize);

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub range: f32,
    pub radiance: [f32; 3],
    pub spot_scale: f32,
    pub spot_offset: f32,
    pub flags: u32,
    pub pad: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<GpuLight>() == LIGHT_STRIDE as usize);

pub const DEBUG_NONE: u32 = 0;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuFrame {
    pub view: [f32; 16],
    pub proj: [f32; 16],
    pub view_proj: [f32; 16],
    pub inv_view_proj: [f32; 16],
    /// The previous frame's view-projection and camera (temporal reuse: glossy reflections' history).
    pub prev_view_proj: [f32; 16],
    pub prev_camera_pos: [f32; 3],
    /// The integrator's recursion limits (Effects::max_depth, min_weight): uniforms, so changing them
    /// compiles no new pipeline.
    pub max_depth: u32,
    pub camera_pos: [f32; 3],
    pub light_count: u32,
    pub env_color: [f32; 3],
    pub env_intensity: f32,
    pub env_ambient: [f32; 3],
    pub env_rotation: f32,
    pub resolution: [u32; 2],
    pub has_env_map: u32,
    pub debug_view: u32,
    pub exposure: f32,
    pub frame_index: u32,
    pub flags: u32,
    pub znear: f32,
    pub tonemap: u32,
    pub auto_exposure: u32,
    pub key: f32,
    pub white: f32,
    pub adapt_dt: f32,
    pub hist_low: f32,
    pub hist_high: f32,
    pub speed_brighten: f32,
    pub speed_darken: f32,
    /// Frames already accumulated by the `reference` or `path` pass (0: it
    /// starts over), also its random seed; and the longest path (reference:
    /// 1 = visibility only; path: bounces), or the `terms` pass's TERM_* bits.
    pub accum_frame: u32,
    pub accum_bounces: u32,
    /// The path tracer's clamp of a sample's radiance (<= 0: none).
    pub path_clamp: f32,
    pub min_weight: f32,
    pub pad_limits: [u32; 3],
    /// Irradiance E_lm (rgb, w unused) of the environment as shaded: rotated
    /// and scaled by its intensity; read where `flags` has FRAME_AMBIENT_SH.
    pub sh_irradiance: [[f32; 4]; SH_IRRADIANCE_COEFFS as usize],
    /// Radiance L_lm (rgb) of the environment as shaded (rotated, scaled,
    /// not convolved: PRT transfer holds the cosine); the first bands² are
    /// read where `flags` has FRAME_AMBIENT_PRT.
    pub sh_radiance: [[f32; 4]; SH_PRT_MAX_COEFFS as usize],
}
const _: () = assert!(
    std::mem::size_of::<GpuFrame>() == 480 + 16 * (SH_IRRADIANCE_COEFFS + SH_PRT_MAX_COEFFS) as usize
);

// [T; 64] has no Default.
impl Default for GpuFrame {
    fn default() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

/// What the luminance pass measured and the exposure it settled on (the
/// GPU's `ExposureState`, glsl/common/exposure.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ExposureState {
    /// The adapted scene luminance the exposure is derived from.
    pub adapted: f32,
    /// key / adapted × the --exposure compensation: what tone mapping applies.
    pub exposure: f32,
    /// This frame's measured luminance (log-average or histogram mean).
    pub target: f32,
    /// exp(mean(log(delta + L))) over the finite pixels.
    pub log_average: f32,
    /// The brightest finite luminance.
    pub max_luminance: f32,
    /// Finite pixels measured.
    pub finite_pixels: u32,
    /// 1 once a frame was measured (adaptation has a history).
    pub valid: u32,
    pub pad: u32,
}

/// Bytes of the state block at the start of the exposure buffer.
pub const EXPOSURE_STATE_BYTES: usize = std::mem::size_of::<ExposureState>();
const _: () = assert!(EXPOSURE_STATE_BYTES == 32);

/// The exposure buffer: the state, then the reduction's per-group partial
/// sums (16 bytes each) and per-group histograms (4 bytes per bin).
pub fn exposure_buffer_bytes() -> u64 {
    use crate::gpu::shared::{HIST_BINS, LUMINANCE_GROUPS};
    (EXPOSURE_STATE_BYTES + LUMINANCE_GROUPS as usize * (16 + 4 * HIST_BINS as usize)) as u64
}
