//! Checks run before the `gltf` crate's validation and readers: the GLB
//! header, unsupported extensions, dangling POSITION and animation target
//! references, and every accessor's type and byte range.

use std::path::Path;

use anyhow::{ensure, Context, Result};
use gltf::accessor::{DataType, Dimensions};

use super::quoted;

/// The `gltf` crate trusts a GLB header's length field (and underflows on a
/// tiny one), so a truncated or corrupt file is rejected here first.
pub(super) fn check_glb_header(bytes: &[u8]) -> Result<()> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    ensure!(bytes.len() >= 20, "truncated GLB: {} bytes is shorter than the GLB header", bytes.len());
    let word = |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    let (version, length) = (word(4), word(8) as usize);
    ensure!(version == 2, "unsupported GLB version {version} (expected 2)");
    ensure!(length >= 20, "corrupt GLB: header length {length} is too small");
    ensure!(
        length <= bytes.len(),
        "truncated GLB: header says {length} bytes but the file has {}",
        bytes.len()
    );
    Ok(())
}

/// Extensions this importer reads; others (instancing, ...) are only used
/// optionally by the file, so it loads without them.
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_texture_transform",
];

pub(super) fn warn_about_ignored_extensions(doc: &gltf::Document, path: &Path) {
    for ext in doc.extensions_used().filter(|e| !SUPPORTED_EXTENSIONS.contains(e)) {
        log::warn!("{}: extension {ext} is not supported and is ignored", path.display());
    }
}

/// The crate's validation indexes the accessor list with each POSITION
/// reference unchecked (a panic on a dangling one), so those are checked
/// before it runs.
pub(super) fn check_position_references(json: &gltf::json::Root) -> Result<()> {
    use gltf::json::{mesh::Semantic, validation::Checked};
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(index) = prim.attributes.get(&Checked::Valid(Semantic::Positions)) {
                ensure!(
                    index.value() < json.accessors.len(),
                    "mesh {m} primitive {p}: POSITION refers to accessor {} but there are only {}",
                    index.value(),
                    json.accessors.len()
                );
            }
        }
    }
    Ok(())
}

/// The crate's validation skips animation channel targets, and its accessors
/// unwrap them, so a dangling node or unknown path is rejected here.
pub(super) fn check_animation_targets(json: &gltf::json::Root) -> Result<()> {
    use gltf::json::validation::Checked;
    for (a, anim) in json.animations.iter().enumerate() {
        let name =
            anim.name.as_deref().map_or_else(|| format!("animation {a}"), |n| format!("animation '{n}'"));
        for (c, channel) in anim.channels.iter().enumerate() {
            let node = channel.target.node.value();
            ensure!(
                node < json.nodes.len(),
                "{name} channel {c}: targets node {node} but there are only {}",
                json.nodes.len()
            );
            ensure!(
                matches!(channel.target.path, Checked::Valid(_)),
                "{name} channel {c}: unknown target path (expected translation, rotation, scale or weights)"
            );
        }
    }
    Ok(())
}

/// What an accessor must look like for one use (glTF spec, "Meshes").
pub(super) struct Expected {
    pub(super) what: &'static str,
    pub(super) dims: Dimensions,
    pub(super) types: &'static [DataType],
    /// Whether u8/u16 vector data must be normalized (everything but joints).
    pub(super) normalized: bool,
}

pub(super) const POSITION: Expected =
    Expected { what: "POSITION", dims: Dimensions::Vec3, types: &[DataType::F32], normalized: true };
pub(super) const NORMAL: Expected =
    Expected { what: "NORMAL", dims: Dimensions::Vec3, types: &[DataType::F32], normalized: true };
pub(super) const TANGENT: Expected =
    Expected { what: "TANGENT", dims: Dimensions::Vec4, types: &[DataType::F32], normalized: true };
pub(super) const TEXCOORD_0: Expected = Expected {
    what: "TEXCOORD_0",
    dims: Dimensions::Vec2,
    types: &[DataType::F32, DataType::U8, DataType::U16],
    normalized: true,
};
pub(super) const INDICES: Expected = Expected {
    what: "indices",
    dims: Dimensions::Scalar,
    types: &[DataType::U8, DataType::U16, DataType::U32],
    normalized: false,
};
pub(super) const JOINTS_0: Expected = Expected {
    what: "JOINTS_0",
    dims: Dimensions::Vec4,
    types: &[DataType::U8, DataType::U16],
    normalized: false,
};
pub(super) const WEIGHTS_0: Expected = Expected {
    what: "WEIGHTS_0",
    dims: Dimensions::Vec4,
    types: &[DataType::F32, DataType::U8, DataType::U16],
    normalized: true,
};

/// Rejects accessors the `gltf` readers would mis-read or panic on: wrong
/// type, zero count, strides smaller than an element, ranges outside their
/// buffer view or the view outside its buffer.
pub(super) fn check_accessor(acc: &gltf::Accessor, expected: &Expected, buffers: &[Vec<u8>]) -> Result<()> {
    let Expected { what, dims, types, normalized } = *expected;
    let context = || format!("{what} accessor {}{}", acc.index(), quoted(acc.name()));
    ensure!(
        acc.dimensions() == dims && types.contains(&acc.data_type()),
        "{}: is {:?} {:?}, expected {dims:?} of {types:?}",
        context(),
        acc.dimensions(),
        acc.data_type()
    );
    ensure!(acc.count() > 0, "{}: count is 0", context());
    let normalized_ints =
        normalized && matches!(acc.data_type(), DataType::U8 | DataType::U16) && dims != Dimensions::Scalar;
    ensure!(!normalized_ints || acc.normalized(), "{}: integer data must be normalized", context());
    match acc.view() {
        Some(view) => {
            check_range(&view, acc.offset(), acc.size(), acc.count(), buffers).with_context(context)?
        }
        None => ensure!(acc.sparse().is_some(), "{}: has neither a bufferView nor sparse data", context()),
    }
    if let Some(sparse) = acc.sparse() {
        let (indices, values) = (sparse.indices(), sparse.values());
        ensure!(sparse.count() > 0, "{}: sparse count is 0", context());
        check_range(&indices.view(), indices.offset(), indices.index_type().size(), sparse.count(), buffers)
            .and_then(|_| check_range(&values.view(), values.offset(), acc.size(), sparse.count(), buffers))
            .with_context(|| format!("{}: sparse data", context()))?;
    }
    Ok(())
}

fn check_range(
    view: &gltf::buffer::View,
    offset: usize,
    element: usize,
    count: usize,
    buffers: &[Vec<u8>],
) -> Result<()> {
    let stride = view.stride().unwrap_or(element);
    ensure!(stride >= element, "byteStride {stride} is smaller than an element ({element} bytes)");
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(offset)?.checked_add(element))
        .context("accessor size overflows")?;
    ensure!(
        end <= view.length(),
        "accessor is out of range: needs {end} bytes of bufferView {} which has {}",
        view.index(),
        view.length()
    );
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    let view_end = view.offset().checked_add(view.length()).context("bufferView size overflows")?;
    ensure!(
        view_end <= buffer_len,
        "bufferView {} is out of range: ends at byte {view_end} of buffer {} which has {buffer_len}",
        view.index(),
        view.buffer().index()
    );
    Ok(())
}
