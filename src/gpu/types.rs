//! Rust mirrors of `glsl/common/types.glsl` (scalar block layout). The
//! sizes are asserted against the strides in `shared_values.rs`, which the
//! shaders' layout is tested against (tests/shared_layout.rs).

use bytemuck::{Pod, Zeroable};

pub use super::shared::{
    ALPHA_BLEND, ALPHA_MASK, ALPHA_OPAQUE, INST_CASTS_SHADOWS, LIGHT_CASTS_SHADOWS, LIGHT_DIRECTIONAL,
    LIGHT_POINT, LIGHT_SPOT, MAT_CASTS_SHADOWS, MAT_DOUBLE_SIDED,
};
use super::shared::{INSTANCE_STRIDE, LIGHT_STRIDE, MATERIAL_STRIDE, VERTEX_STRIDE};

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
    pub pad: [u32; 2],
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
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuFrame {
    pub view: [f32; 16],
    pub proj: [f32; 16],
    pub view_proj: [f32; 16],
    pub inv_view_proj: [f32; 16],
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
}
const _: () = assert!(std::mem::size_of::<GpuFrame>() == 336);
