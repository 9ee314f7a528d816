//! A scene material as the shaders read it (glsl/common/types.glsl `Material`): factors, texture
//! slots and each slot's KHR_texture_transform.

use super::environment::HALF_MAX;
use super::types::{GpuMaterial, ALPHA_BLEND, ALPHA_MASK, ALPHA_OPAQUE, MAT_CASTS_SHADOWS, MAT_DOUBLE_SIDED};
use crate::scene::{AlphaMode, Material, TextureRef, UvTransform};

fn tex_index(t: &Option<TextureRef>) -> i32 {
    t.map(|t| t.texture as i32).unwrap_or(-1)
}

fn uv_rows(t: &Option<TextureRef>) -> [[f32; 3]; 2] {
    t.map_or(UvTransform::IDENTITY, |t| t.transform).rows
}

/// Emission is limited to half's range (where primary emission was once stored; kept so scenes keep
/// their look). Clamped here, where every material passes, so every mode and bounce shades the same.
pub const MAX_EMISSIVE: f32 = HALF_MAX;

pub(super) fn gpu_material(m: &Material) -> GpuMaterial {
    let emissive = m.emissive.map(|e| e.min(MAX_EMISSIVE));
    if emissive != m.emissive {
        log::warn!(
            "material '{}': emissive {:?} clamped to {MAX_EMISSIVE} (the half-float range)",
            m.name,
            m.emissive
        );
    }
    let c = &m.clearcoat;
    GpuMaterial {
        base_color: m.base_color,
        emissive,
        metallic: m.metallic,
        roughness: m.roughness,
        normal_scale: m.normal_scale,
        occlusion_strength: m.occlusion_strength,
        alpha_cutoff: m.alpha_cutoff,
        transmission: m.transmission,
        ior: m.ior,
        alpha_mode: match m.alpha_mode {
            AlphaMode::Opaque => ALPHA_OPAQUE,
            AlphaMode::Mask => ALPHA_MASK,
            AlphaMode::Blend => ALPHA_BLEND,
        },
        flags: if m.double_sided { MAT_DOUBLE_SIDED } else { 0 }
            | if m.casts_shadows { MAT_CASTS_SHADOWS } else { 0 },
        tex_base_color: tex_index(&m.base_color_texture),
        tex_metallic_roughness: tex_index(&m.metallic_roughness_texture),
        tex_normal: tex_index(&m.normal_texture),
        tex_occlusion: tex_index(&m.occlusion_texture),
        tex_emissive: tex_index(&m.emissive_texture),
        tex_transmission: tex_index(&m.transmission_texture),
        volume_sigma: m.volume_sigma(),
        specular: m.specular,
        tex_specular: tex_index(&m.specular_texture),
        tex_specular_color: tex_index(&m.specular_color_texture),
        uv_transforms: [
            &m.base_color_texture,
            &m.metallic_roughness_texture,
            &m.normal_texture,
            &m.occlusion_texture,
            &m.emissive_texture,
            &m.transmission_texture,
            &m.specular_texture,
            &m.specular_color_texture,
        ]
        .map(uv_rows),
        specular_color: m.specular_color,
        pad: 0,
        clearcoat: c.factor,
        clearcoat_roughness: c.roughness,
        clearcoat_normal_scale: c.normal_scale,
        tex_clearcoat: tex_index(&c.texture),
        tex_clearcoat_roughness: tex_index(&c.roughness_texture),
        tex_clearcoat_normal: tex_index(&c.normal_texture),
        uv_clearcoat: [&c.texture, &c.roughness_texture, &c.normal_texture].map(uv_rows),
    }
}
