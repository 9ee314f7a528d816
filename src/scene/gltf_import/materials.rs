//! Materials: glTF metallic-roughness with the emissive strength, IOR,
//! specular, clearcoat (clearcoat.rs), transmission and volume extensions, their textures assigned to slots with
//! each reference's KHR_texture_transform.

use anyhow::{ensure, Context, Result};
use glam::Vec3;
use serde::Deserialize;

use gltf::json::extensions::texture::TextureTransform;

use super::clearcoat::convert_clearcoat;
use super::images::TextureSlots;
use super::values::sane;
use crate::scene::{AlphaMode, Material, TextureRef, UvTransform};

pub(super) const TRANSFORM: &str = "KHR_texture_transform";

pub(super) fn convert_material(
    m: &gltf::Material,
    doc: &gltf::Document,
    slots: &mut TextureSlots,
) -> Result<Material> {
    let name = m.name().map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_string);
    let pbr = m.pbr_metallic_roughness();
    let mut slot =
        |info: Option<gltf::texture::Info>, srgb: bool, what: &str| -> Result<Option<TextureRef>> {
            let Some(i) = info else { return Ok(None) };
            let t = i.texture_transform();
            let transform = t.as_ref().map(|t| TransformExt {
                offset: t.offset(),
                rotation: t.rotation(),
                scale: t.scale(),
                tex_coord: t.tex_coord(),
            });
            let (tex_coord, transform) = uv_transform(transform, i.tex_coord(), what)?;
            Ok(Some(slots.slot(i.texture(), tex_coord, transform, srgb, &name)))
        };
    let base_color_texture = slot(pbr.base_color_texture(), true, "baseColorTexture")?;
    let metallic_roughness_texture =
        slot(pbr.metallic_roughness_texture(), false, "metallicRoughnessTexture")?;
    let emissive_texture = slot(m.emissive_texture(), true, "emissiveTexture")?;
    let specular = m.specular();
    let specular_texture =
        slot(specular.as_ref().and_then(|s| s.specular_texture()), false, "specularTexture")?;
    let specular_color_texture =
        slot(specular.as_ref().and_then(|s| s.specular_color_texture()), true, "specularColorTexture")?;
    let transmission = m.transmission();
    let transmission_texture =
        slot(transmission.as_ref().and_then(|t| t.transmission_texture()), false, "transmissionTexture")?;
    // The crate parses the extension on textureInfo only; normal and
    // occlusion references carry it as raw JSON.
    let mut raw_slot = |texture: gltf::Texture, tex_coord: u32, t: Option<TextureTransform>, what: &str| {
        let transform = t.map(|t| TransformExt {
            offset: t.offset.0,
            rotation: t.rotation.0,
            scale: t.scale.0,
            tex_coord: t.tex_coord,
        });
        let (tex_coord, transform) = uv_transform(transform, tex_coord, what)?;
        anyhow::Ok(slots.slot(texture, tex_coord, transform, false, &name))
    };
    let normal = m.normal_texture();
    let normal_texture = match &normal {
        Some(n) => {
            let t = json_transform(n.extension_value(TRANSFORM), "normalTexture")?;
            Some(raw_slot(n.texture(), n.tex_coord(), t, "normalTexture")?)
        }
        None => None,
    };
    let occlusion = m.occlusion_texture();
    let occlusion_texture = match &occlusion {
        Some(o) => {
            let t = json_transform(o.extension_value(TRANSFORM), "occlusionTexture")?;
            Some(raw_slot(o.texture(), o.tex_coord(), t, "occlusionTexture")?)
        }
        None => None,
    };
    let clearcoat = convert_clearcoat(m, doc, |r| raw_slot(r.texture, r.tex_coord, r.transform, r.what))?;
    let strength = m.emissive_strength().unwrap_or(1.0);
    Ok(Material {
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
        specular: specular.as_ref().map_or(1.0, |s| s.specular_factor()),
        specular_texture,
        specular_color: specular.as_ref().map_or([1.0; 3], |s| s.specular_color_factor()),
        specular_color_texture,
        clearcoat,
        casts_shadows: true,
        name,
    })
}

/// A KHR_texture_transform the crate leaves as raw JSON, parsed.
pub(super) fn json_transform(
    ext: Option<&gltf::json::Value>,
    what: &str,
) -> Result<Option<TextureTransform>> {
    ext.map(|v| TextureTransform::deserialize(v).with_context(|| format!("{what}: malformed {TRANSFORM}")))
        .transpose()
}

/// KHR_texture_transform's numbers, from either form the crate gives them in.
struct TransformExt {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    tex_coord: Option<u32>,
}

/// A reference's (texCoord, transform): the extension's texCoord overrides
/// the reference's; its numbers must be finite.
fn uv_transform(ext: Option<TransformExt>, tex_coord: u32, what: &str) -> Result<(u32, UvTransform)> {
    let Some(TransformExt { offset, rotation, scale, tex_coord: set }) = ext else {
        return Ok((tex_coord, UvTransform::IDENTITY));
    };
    ensure!(
        offset.iter().chain(&scale).chain([&rotation]).all(|&v| sane(v)),
        "{what}: {TRANSFORM} offset {offset:?}, rotation {rotation}, scale {scale:?} must be finite"
    );
    Ok((set.unwrap_or(tex_coord), UvTransform::from_gltf(offset, rotation, scale)))
}
