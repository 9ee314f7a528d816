//! Materials: glTF metallic-roughness with the emissive strength, IOR and
//! transmission extensions, their textures assigned to slots.

use glam::Vec3;

use super::images::TextureSlots;
use crate::scene::{AlphaMode, Material};

pub(super) fn convert_material(m: &gltf::Material, slots: &mut TextureSlots) -> Material {
    let name = m.name().map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_string);
    let pbr = m.pbr_metallic_roughness();
    let mut slot = |info: Option<gltf::texture::Info>, srgb: bool| {
        info.map(|i| slots.slot(i.texture(), i.tex_coord(), srgb, &name))
    };
    let base_color_texture = slot(pbr.base_color_texture(), true);
    let metallic_roughness_texture = slot(pbr.metallic_roughness_texture(), false);
    let emissive_texture = slot(m.emissive_texture(), true);
    let transmission = m.transmission();
    let transmission_texture = slot(transmission.as_ref().and_then(|t| t.transmission_texture()), false);
    let normal = m.normal_texture();
    let normal_texture = normal.as_ref().map(|n| slots.slot(n.texture(), n.tex_coord(), false, &name));
    let occlusion = m.occlusion_texture();
    let occlusion_texture = occlusion.as_ref().map(|o| slots.slot(o.texture(), o.tex_coord(), false, &name));
    let strength = m.emissive_strength().unwrap_or(1.0);
    Material {
        base_color: pbr.base_color_factor(),
        base_color_texture,
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        metallic_roughness_texture,
        normal_texture,
        normal_scale: normal.as_ref().map_or(1.0, |n| n.scale()),
        occlusion_texture,
        occlusion_strength: occlusion.as_ref().map_or(1.0, |o| o.strength()),
        emissive: (Vec3::from(m.emissive_factor()) * strength).to_array(),
        emissive_texture,
        alpha_mode: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask,
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        alpha_cutoff: m.alpha_cutoff().unwrap_or(0.5),
        double_sided: m.double_sided(),
        transmission: transmission.as_ref().map_or(0.0, |t| t.transmission_factor()),
        // (thicknessFactor is for rasterizers that cannot trace the mesh.)
        attenuation_color: m.volume().map_or([1.0; 3], |v| v.attenuation_color()),
        attenuation_distance: m.volume().map_or(f32::INFINITY, |v| v.attenuation_distance()),
        transmission_texture,
        ior: m.ior().unwrap_or(1.5),
        casts_shadows: true,
        name,
    }
}
