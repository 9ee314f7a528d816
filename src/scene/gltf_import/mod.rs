//! glTF 2.0 (.gltf with external or data-URI buffers, .glb) into a [`Scene`].
//!
//! The `gltf` crate parses and validates the JSON; buffers and images are read here rather than with
//! `gltf::import` so errors name the missing file, and every accessor is range- and type-checked
//! first (the crate's readers panic or silently stop on bad ranges).
//!
//! Modules: `checks` (GLB header, dangling references, accessors), `buffers` (buffers and URIs),
//! `geometry` (primitives, attributes, normals, tangents), `materials`, `images` (texture slots,
//! samplers, parallel decoding), `nodes` (hierarchy, cameras, lights), `animation` (animations, skins).

mod animation;
mod buffers;
mod checks;
mod clearcoat;
mod geometry;
mod images;
mod materials;
mod nodes;
#[cfg(test)]
mod tests;
mod values;

use std::path::Path;

use anyhow::{Context, Result};

use super::{Material, Scene};
use animation::{convert_animations, convert_skins};
use buffers::load_buffers;
use checks::{
    check_animation_targets, check_glb_header, check_position_references, warn_about_ignored_extensions,
};
use geometry::convert_mesh;
use images::TextureSlots;
use materials::convert_material;
use nodes::build_nodes;

/// Loads a .gltf or .glb file. Every error names `path` and the offending
/// element (mesh, primitive, buffer, image, node).
pub fn load(path: &Path) -> Result<Scene> {
    import(path).with_context(|| path.display().to_string())
}

fn import(path: &Path) -> Result<Scene> {
    let bytes = std::fs::read(path).context("cannot read glTF file")?;
    check_glb_header(&bytes)?;
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(&bytes).context("cannot parse glTF")?;
    let json = document.into_json();
    check_position_references(&json)?;
    check_animation_targets(&json)?;
    let doc = gltf::Document::from_json(json).context("invalid glTF")?;
    warn_about_ignored_extensions(&doc, path);
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = load_buffers(&doc, base, blob)?;

    let mut scene = Scene::default();
    let mut slots = TextureSlots::default();
    check_values(&doc)?;
    scene.materials = doc
        .materials()
        .map(|m| {
            convert_material(&m, &doc, &mut slots)
                .with_context(|| format!("material {}{}", m.index().unwrap_or(0), quoted(m.name())))
        })
        .collect::<Result<_>>()?;
    let normal_mapped: Vec<bool> = scene
        .materials
        .iter()
        .map(|m| m.normal_texture.is_some() || m.clearcoat.normal_texture.is_some())
        .collect();
    // Primitives without a material use a default appended after the file's.
    let default_material = scene.materials.len();
    for mesh in doc.meshes() {
        scene.meshes.push(convert_mesh(&mesh, &buffers, &normal_mapped, default_material)?);
    }
    if scene.meshes.iter().flat_map(|m| &m.primitives).any(|p| p.material == default_material) {
        scene.materials.push(Material::default());
    }
    scene.textures = slots.decode(&doc, base, &buffers)?;
    build_nodes(&doc, &mut scene)?;
    convert_skins(&doc, &buffers, &mut scene)?;
    scene.animations = convert_animations(&doc, &buffers, path)?;
    Ok(scene)
}

/// Every material, light and camera of the file, in range (see `values`).
fn check_values(doc: &gltf::Document) -> Result<()> {
    for m in doc.materials() {
        let index = m.index().unwrap_or(0);
        values::check_material(&m).with_context(|| format!("material {index}{}", quoted(m.name())))?;
    }
    for light in doc.lights().into_iter().flatten() {
        values::check_light(&light)
            .with_context(|| format!("light {}{}", light.index(), quoted(light.name())))?;
    }
    for cam in doc.cameras() {
        values::check_camera(&cam)
            .with_context(|| format!("camera {}{}", cam.index(), quoted(cam.name())))?;
    }
    Ok(())
}

fn quoted(name: Option<&str>) -> String {
    name.map(|n| format!(" '{n}'")).unwrap_or_default()
}
