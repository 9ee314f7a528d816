//! KHR_materials_clearcoat, which the `gltf` crate does not parse: the material's raw extension JSON,
//! its factors checked and its three texture references slotted like the core ones.

use anyhow::{ensure, Context, Result};
use gltf::json::extensions::texture::TextureTransform;
use gltf::json::material::NormalTexture;
use gltf::json::texture::Info;
use serde::Deserialize;

use super::materials::{json_transform, TRANSFORM};
use super::values::sane;
use crate::scene::{Clearcoat, TextureRef};

pub(super) const EXTENSION: &str = "KHR_materials_clearcoat";

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct ClearcoatJson {
    #[serde(default)]
    clearcoat_factor: f32,
    clearcoat_texture: Option<Info>,
    #[serde(default)]
    clearcoat_roughness_factor: f32,
    clearcoat_roughness_texture: Option<Info>,
    clearcoat_normal_texture: Option<NormalTexture>,
}

/// A texture reference of the extension as the importer slots it: the texture, its texCoord and its
/// raw KHR_texture_transform (if any).
pub(super) struct RawReference<'a> {
    pub texture: gltf::Texture<'a>,
    pub tex_coord: u32,
    pub transform: Option<TextureTransform>,
    pub what: &'static str,
}

/// The material's coat (the default, factor 0, without the extension). `slot` turns a reference into
/// a texture slot (linear: the coat's textures hold data).
pub(super) fn convert_clearcoat<'a>(
    m: &gltf::Material,
    doc: &'a gltf::Document,
    mut slot: impl FnMut(RawReference<'a>) -> Result<TextureRef>,
) -> Result<Clearcoat> {
    let Some(value) = m.extension_value(EXTENSION) else { return Ok(Clearcoat::default()) };
    let json = ClearcoatJson::deserialize(value).with_context(|| format!("malformed {EXTENSION}"))?;
    let factor = json.clearcoat_factor;
    let roughness = json.clearcoat_roughness_factor;
    ensure!(
        sane(factor) && (0.0..=1.0).contains(&factor),
        "{EXTENSION} clearcoatFactor {factor} must be within [0, 1]"
    );
    ensure!(
        sane(roughness) && (0.0..=1.0).contains(&roughness),
        "{EXTENSION} clearcoatRoughnessFactor {roughness} must be within [0, 1]"
    );
    let texture = |index: usize, what: &str| {
        let count = doc.textures().len();
        doc.textures().nth(index).with_context(|| {
            format!("{EXTENSION} {what} refers to texture {index} but there are only {count}")
        })
    };
    let mut info = |i: Option<Info>, what: &'static str| -> Result<Option<TextureRef>> {
        let Some(i) = i else { return Ok(None) };
        let transform = i.extensions.and_then(|e| e.texture_transform);
        let reference = RawReference {
            texture: texture(i.index.value(), what)?,
            tex_coord: i.tex_coord,
            transform,
            what,
        };
        slot(reference).map(Some)
    };
    let coat_texture = info(json.clearcoat_texture, "clearcoatTexture")?;
    let roughness_texture = info(json.clearcoat_roughness_texture, "clearcoatRoughnessTexture")?;
    let (normal_texture, normal_scale) = match json.clearcoat_normal_texture {
        None => (None, 1.0),
        Some(n) => {
            let what = "clearcoatNormalTexture";
            ensure!(sane(n.scale), "{EXTENSION} {what}.scale {} must be finite", n.scale);
            let raw = n.extensions.as_ref().and_then(|e| e.others.get(TRANSFORM));
            let transform = json_transform(raw, what)?;
            let reference = RawReference {
                texture: texture(n.index.value(), what)?,
                tex_coord: n.tex_coord,
                transform,
                what,
            };
            (Some(slot(reference)?), n.scale)
        }
    };
    Ok(Clearcoat {
        factor,
        texture: coat_texture,
        roughness,
        roughness_texture,
        normal_texture,
        normal_scale,
    })
}
