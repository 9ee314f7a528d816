//! glTF 2.0 (.gltf with external or data-URI buffers, .glb) into a [`Scene`].
//!
//! The `gltf` crate parses and validates the JSON; buffers and images are
//! read here rather than with `gltf::import` so that errors can name the file
//! that is missing, and every accessor is range- and type-checked before the
//! crate's readers touch it (they panic or silently stop on bad ranges).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::{anyhow, bail, ensure, Context, Result};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::texture::{MagFilter, MinFilter, WrappingMode};

use super::animation::{Animation, AnimationChannel, Channel, Interpolation};
use super::skin::{Skin, SkinWeights};
use super::tangents::{
    bounds_of, fallback_tangent, fill_fallback_tangents, flatten_with_face_normals, generate_tangents,
    smooth_normals,
};
use super::{
    AlphaMode, Camera, Filter, Light, LightKind, Material, Mesh, Node, Object, Primitive, SamplerDesc, Scene,
    Texture, TextureRef, Transform, Vertex, Wrap,
};

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
    scene.materials = doc.materials().map(|m| convert_material(&m, &mut slots)).collect();
    let normal_mapped: Vec<bool> = scene.materials.iter().map(|m| m.normal_texture.is_some()).collect();
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

/// The `gltf` crate trusts a GLB header's length field (and underflows on a
/// tiny one), so a truncated or corrupt file is rejected here first.
fn check_glb_header(bytes: &[u8]) -> Result<()> {
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

/// Extensions this importer reads; others (instancing, texture transforms,
/// ...) are only used optionally by the file, so it loads without them.
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
];

fn warn_about_ignored_extensions(doc: &gltf::Document, path: &Path) {
    for ext in doc.extensions_used().filter(|e| !SUPPORTED_EXTENSIONS.contains(e)) {
        log::warn!("{}: extension {ext} is not supported and is ignored", path.display());
    }
}

/// The crate's validation indexes the accessor list with each POSITION
/// reference unchecked (a panic on a dangling one), so those are checked
/// before it runs.
fn check_position_references(json: &gltf::json::Root) -> Result<()> {
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
fn check_animation_targets(json: &gltf::json::Root) -> Result<()> {
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

// ---------------------------------------------------------------------------
// Buffers and URIs

fn load_buffers(doc: &gltf::Document, base: &Path, mut blob: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>> {
    doc.buffers()
        .map(|buffer| {
            let what = || format!("buffer {}{}", buffer.index(), quoted(buffer.name()));
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or_else(|| anyhow!("GLB has no BIN chunk")),
                gltf::buffer::Source::Uri(uri) => read_uri(uri, base),
            }
            .with_context(what)?;
            ensure!(
                data.len() >= buffer.length(),
                "{}: holds {} bytes but byteLength is {}",
                what(),
                data.len(),
                buffer.length()
            );
            Ok(data)
        })
        .collect()
}

/// Reads a buffer or image URI: base64 data URIs, or files relative to the
/// glTF (percent-encoded, as the spec requires).
fn read_uri(uri: &str, base: &Path) -> Result<Vec<u8>> {
    if uri.starts_with("data:") {
        // The crate's decoder only handles the data scheme on this path.
        let data = gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
            .map_err(|e| anyhow!("invalid data URI: {e}"))?;
        return Ok(data.0);
    }
    let path = resolve_uri(uri, base)?;
    std::fs::read(&path).with_context(|| format!("cannot read '{}'", path.display()))
}

fn resolve_uri(uri: &str, base: &Path) -> Result<PathBuf> {
    let decoded = percent_decode(uri).with_context(|| format!("invalid URI '{uri}'"))?;
    if let Some(rest) = decoded.strip_prefix("file://").or_else(|| decoded.strip_prefix("file:")) {
        return Ok(PathBuf::from(rest));
    }
    ensure!(
        !decoded.contains("://"),
        "unsupported URI scheme in '{uri}' (only relative paths and data URIs)"
    );
    Ok(base.join(decoded))
}

fn percent_decode(s: &str) -> Result<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = s.get(i + 1..i + 3).context("truncated percent escape")?;
            out.push(u8::from_str_radix(hex, 16).with_context(|| format!("bad percent escape '%{hex}'"))?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).context("percent-decoded URI is not UTF-8")
}

fn quoted(name: Option<&str>) -> String {
    name.map(|n| format!(" '{n}'")).unwrap_or_default()
}

// ---------------------------------------------------------------------------
// Accessor checks

/// What an accessor must look like for one use (glTF spec, "Meshes").
struct Expected {
    what: &'static str,
    dims: Dimensions,
    types: &'static [DataType],
    /// Whether u8/u16 vector data must be normalized (everything but joints).
    normalized: bool,
}

const POSITION: Expected =
    Expected { what: "POSITION", dims: Dimensions::Vec3, types: &[DataType::F32], normalized: true };
const NORMAL: Expected =
    Expected { what: "NORMAL", dims: Dimensions::Vec3, types: &[DataType::F32], normalized: true };
const TANGENT: Expected =
    Expected { what: "TANGENT", dims: Dimensions::Vec4, types: &[DataType::F32], normalized: true };
const TEXCOORD_0: Expected = Expected {
    what: "TEXCOORD_0",
    dims: Dimensions::Vec2,
    types: &[DataType::F32, DataType::U8, DataType::U16],
    normalized: true,
};
const INDICES: Expected = Expected {
    what: "indices",
    dims: Dimensions::Scalar,
    types: &[DataType::U8, DataType::U16, DataType::U32],
    normalized: false,
};
const JOINTS_0: Expected = Expected {
    what: "JOINTS_0",
    dims: Dimensions::Vec4,
    types: &[DataType::U8, DataType::U16],
    normalized: false,
};
const WEIGHTS_0: Expected = Expected {
    what: "WEIGHTS_0",
    dims: Dimensions::Vec4,
    types: &[DataType::F32, DataType::U8, DataType::U16],
    normalized: true,
};

/// Rejects accessors the `gltf` readers would mis-read or panic on: wrong
/// type, zero count, strides smaller than an element, ranges outside their
/// buffer view or the view outside its buffer.
fn check_accessor(acc: &gltf::Accessor, expected: &Expected, buffers: &[Vec<u8>]) -> Result<()> {
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

// ---------------------------------------------------------------------------
// Meshes

fn convert_mesh(
    mesh: &gltf::Mesh,
    buffers: &[Vec<u8>],
    normal_mapped: &[bool],
    default_material: usize,
) -> Result<Mesh> {
    let name = mesh.name().map(str::to_string).unwrap_or_else(|| format!("mesh {}", mesh.index()));
    let mut primitives = Vec::new();
    for prim in mesh.primitives() {
        let context = || format!("mesh '{name}' primitive {}", prim.index());
        let material = prim.material().index().unwrap_or(default_material);
        let needs_tangents = normal_mapped.get(material).copied().unwrap_or(false);
        if let Some(mut p) = convert_primitive(&prim, buffers, needs_tangents).with_context(context)? {
            p.material = material;
            primitives.push(p);
        } else {
            log::warn!("{}: {:?} primitives are not supported, skipped", context(), prim.mode());
        }
    }
    Ok(Mesh { name, primitives })
}

/// A triangle primitive with all renderer attributes filled in, or None for
/// points and lines.
fn convert_primitive(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    needs_tangents: bool,
) -> Result<Option<Primitive>> {
    if !matches!(prim.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
        return Ok(None);
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let positions = read_positions(prim, &reader, buffers)?;
    let count = positions.len();
    let mut vertices: Vec<Vertex> =
        positions.iter().map(|p| Vertex { position: *p, ..Default::default() }).collect();

    let attribute = |semantic| prim.get(&semantic);
    let normals = read_attribute(attribute(gltf::Semantic::Normals), &NORMAL, count, buffers, || {
        reader.read_normals().map(|it| it.collect::<Vec<_>>())
    })?;
    let uvs = read_attribute(attribute(gltf::Semantic::TexCoords(0)), &TEXCOORD_0, count, buffers, || {
        reader.read_tex_coords(0).map(|it| it.into_f32().collect::<Vec<_>>())
    })?;
    for (v, uv) in vertices.iter_mut().zip(uvs.unwrap_or_default()) {
        v.uv = if Vec2::from(uv).is_finite() { uv } else { [0.0; 2] };
    }
    let tangents = read_attribute(attribute(gltf::Semantic::Tangents), &TANGENT, count, buffers, || {
        reader.read_tangents().map(|it| it.collect::<Vec<_>>())
    })?;
    let indices = triangle_list(prim.mode(), read_indices(prim, &reader, buffers, count)?);
    let skin = read_skin_weights(prim, &reader, count, buffers)?;

    let (mut vertices, indices, tangents, skin) = match normals {
        Some(normals) => {
            apply_normals(&mut vertices, &normals, &indices);
            (vertices, indices, tangents, skin)
        }
        // The spec asks for flat normals when a primitive has none, and for
        // its tangents (if any) to be ignored then.
        None => {
            // Flattening makes one vertex per index; the weights follow.
            let skin = skin.map(|s| SkinWeights {
                joints: indices.iter().map(|&i| s.joints[i as usize]).collect(),
                weights: indices.iter().map(|&i| s.weights[i as usize]).collect(),
            });
            let (vertices, indices) = flatten_with_face_normals(&vertices, &indices);
            (vertices, indices, None, skin)
        }
    };
    match tangents {
        Some(t) => apply_tangents(&mut vertices, &t),
        None if needs_tangents => generate_tangents(&mut vertices, &indices),
        None => fill_fallback_tangents(&mut vertices),
    }
    let bounds = bounds_of(&vertices);
    Ok(Some(Primitive { vertices, indices, material: 0, bounds, skin }))
}

/// JOINTS_0 + WEIGHTS_0 (both or neither), checked and renormalized.
fn read_skin_weights<'a, 's, F>(
    prim: &gltf::Primitive,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    count: usize,
    buffers: &[Vec<u8>],
) -> Result<Option<SkinWeights>>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let joints = read_attribute(prim.get(&gltf::Semantic::Joints(0)), &JOINTS_0, count, buffers, || {
        reader.read_joints(0).map(|it| it.into_u16().map(|j| j.map(u32::from)).collect::<Vec<_>>())
    })?;
    let weights = read_attribute(prim.get(&gltf::Semantic::Weights(0)), &WEIGHTS_0, count, buffers, || {
        reader.read_weights(0).map(|it| it.into_f32().collect::<Vec<_>>())
    })?;
    match (joints, weights) {
        (Some(j), Some(w)) => Ok(Some(SkinWeights::new(j, w)?)),
        (None, None) => Ok(None),
        (Some(_), None) => bail!("has JOINTS_0 but no WEIGHTS_0"),
        (None, Some(_)) => bail!("has WEIGHTS_0 but no JOINTS_0"),
    }
}

fn read_positions<'a, 's, F>(
    prim: &gltf::Primitive,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    buffers: &[Vec<u8>],
) -> Result<Vec<[f32; 3]>>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let acc = prim.get(&gltf::Semantic::Positions).context("has no POSITION attribute")?;
    check_accessor(&acc, &POSITION, buffers)?;
    let positions: Vec<[f32; 3]> = reader.read_positions().context("cannot read POSITION")?.collect();
    ensure!(positions.len() == acc.count(), "POSITION: read {} of {} vertices", positions.len(), acc.count());
    if let Some(i) = positions.iter().position(|p| !Vec3::from(*p).is_finite()) {
        bail!("vertex {i} has a non-finite position {:?}", positions[i]);
    }
    Ok(positions)
}

/// Checks and reads an optional vertex attribute whose count must match
/// POSITION's. `read` runs the crate's typed reader once the checks pass.
fn read_attribute<T>(
    acc: Option<gltf::Accessor>,
    expected: &Expected,
    vertex_count: usize,
    buffers: &[Vec<u8>],
    read: impl FnOnce() -> Option<Vec<T>>,
) -> Result<Option<Vec<T>>> {
    let Some(acc) = acc else { return Ok(None) };
    let what = expected.what;
    check_accessor(&acc, expected, buffers)?;
    ensure!(
        acc.count() == vertex_count,
        "{what} has {} elements but POSITION has {vertex_count}",
        acc.count()
    );
    let values = read().with_context(|| format!("cannot read {what}"))?;
    ensure!(values.len() == vertex_count, "{what}: read {} of {vertex_count} elements", values.len());
    Ok(Some(values))
}

/// Index list widened to u32 (0..n for non-indexed primitives), with every
/// index checked against the vertex count.
fn read_indices<'a, 's, F>(
    prim: &gltf::Primitive,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    buffers: &[Vec<u8>],
    vertex_count: usize,
) -> Result<Vec<u32>>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let Some(acc) = prim.indices() else {
        let n = u32::try_from(vertex_count).context("too many vertices for 32-bit indices")?;
        return Ok((0..n).collect());
    };
    check_accessor(&acc, &INDICES, buffers)?;
    let indices: Vec<u32> = reader.read_indices().context("cannot read indices")?.into_u32().collect();
    ensure!(indices.len() == acc.count(), "indices: read {} of {}", indices.len(), acc.count());
    if let Some(i) = indices.iter().position(|&i| i as usize >= vertex_count) {
        bail!(
            "index {} (element {i}) is out of range: the primitive has {vertex_count} vertices",
            indices[i]
        );
    }
    Ok(indices)
}

/// Strips and fans become lists with the winding the spec prescribes; a list
/// with a partial last triangle loses it.
fn triangle_list(mode: Mode, indices: Vec<u32>) -> Vec<u32> {
    let n = indices.len();
    match mode {
        Mode::TriangleStrip if n >= 3 => (0..n - 2)
            .flat_map(|i| {
                let odd = i % 2;
                [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
            })
            .collect(),
        Mode::TriangleFan if n >= 3 => {
            (1..n - 1).flat_map(|i| [indices[i], indices[i + 1], indices[0]]).collect()
        }
        Mode::TriangleStrip | Mode::TriangleFan => Vec::new(),
        _ => {
            if !n.is_multiple_of(3) {
                log::warn!("index count {n} is not a multiple of 3: dropping the partial triangle");
            }
            let mut indices = indices;
            indices.truncate(n - n % 3);
            indices
        }
    }
}

/// Normalises the file's normals; zero or non-finite ones (seen in some
/// exporters' output) are replaced by generated smooth normals.
fn apply_normals(vertices: &mut [Vertex], normals: &[[f32; 3]], indices: &[u32]) {
    let usable = |n: &[f32; 3]| Vec3::from(*n).try_normalize();
    let fallback = if normals.iter().all(|n| usable(n).is_some()) {
        Vec::new()
    } else {
        let positions: Vec<Vec3> = vertices.iter().map(|v| Vec3::from(v.position)).collect();
        let triangles: Vec<[usize; 3]> =
            indices.chunks_exact(3).map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
        smooth_normals(&positions, &triangles)
    };
    for (i, (v, n)) in vertices.iter_mut().zip(normals).enumerate() {
        v.normal = usable(n).unwrap_or_else(|| fallback[i]).to_array();
    }
}

/// File tangents, made orthogonal to the (possibly regenerated) normal and
/// with w reduced to its sign; unusable ones (zero, non-finite, parallel to
/// the normal) get an orthogonal fallback.
fn apply_tangents(vertices: &mut [Vertex], tangents: &[[f32; 4]]) {
    for (v, t) in vertices.iter_mut().zip(tangents) {
        let n = Vec3::from(v.normal);
        let t = Vec4::from(*t);
        let dir = (t.truncate() - n * n.dot(t.truncate())).try_normalize();
        v.tangent = match dir {
            Some(dir) if t.w.is_finite() => dir.extend(if t.w < 0.0 { -1.0 } else { 1.0 }).to_array(),
            _ => fallback_tangent(n).to_array(),
        };
    }
}

// ---------------------------------------------------------------------------
// Materials and textures

/// Assigns `Scene::textures` slots to (image, sampler, colour space)
/// combinations while materials are converted; images are decoded later in
/// one parallel pass.
#[derive(Default)]
struct TextureSlots {
    keys: Vec<(usize, SamplerDesc, bool)>,
}

impl TextureSlots {
    fn slot(&mut self, texture: gltf::Texture, tex_coord: u32, srgb: bool, material: &str) -> TextureRef {
        if tex_coord != 0 {
            log::warn!(
                "material '{material}': texture {} uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is loaded",
                texture.index()
            );
        }
        let key = (texture.source().index(), sampler_desc(&texture.sampler()), srgb);
        let index = self.keys.iter().position(|k| *k == key).unwrap_or_else(|| {
            self.keys.push(key);
            self.keys.len() - 1
        });
        TextureRef { texture: index, tex_coord }
    }

    /// Decodes every image used by a slot (each once, on all cores) and
    /// returns the textures in slot order.
    fn decode(&self, doc: &gltf::Document, base: &Path, buffers: &[Vec<u8>]) -> Result<Vec<Texture>> {
        let mut used: Vec<usize> = self.keys.iter().map(|k| k.0).collect();
        used.sort_unstable();
        used.dedup();
        let images: Vec<gltf::Image> = doc.images().collect();
        let sources: Vec<ImageSource> = used.iter().map(|&i| ImageSource::new(&images[i], base)).collect();
        let mut decoded: Vec<Option<DecodedImage>> =
            decode_parallel(&sources, buffers)?.into_iter().map(Some).collect();
        // Pixels move into their image's last texture; only an image used
        // with several samplers or colour spaces is copied.
        let mut last_use = vec![0; used.len()];
        let positions: Vec<usize> = self.keys.iter().filter_map(|k| used.binary_search(&k.0).ok()).collect();
        ensure!(positions.len() == self.keys.len(), "internal error: texture image not decoded");
        for (slot, &k) in positions.iter().enumerate() {
            last_use[k] = slot;
        }
        let mut textures = Vec::with_capacity(self.keys.len());
        for (slot, (&k, &(_, sampler, srgb))) in positions.iter().zip(&self.keys).enumerate() {
            let image = if last_use[k] == slot { decoded[k].take() } else { decoded[k].clone() };
            let image = image.context("internal error: texture image used after its last use")?;
            let name = sources[k].name.clone();
            textures.push(Texture {
                name,
                width: image.width,
                height: image.height,
                rgba8: image.rgba8,
                srgb,
                sampler,
            });
        }
        Ok(textures)
    }
}

#[derive(Clone)]
struct DecodedImage {
    width: u32,
    height: u32,
    rgba8: Vec<u8>,
}

/// Where one image's encoded bytes live, detached from the document so the
/// decode threads need nothing but the buffers.
struct ImageSource {
    name: String,
    location: ImageLocation,
}

enum ImageLocation {
    /// A URI (file or data) relative to `base`.
    Uri { uri: String, base: PathBuf },
    /// A byte range of a buffer.
    View { buffer: usize, offset: usize, length: usize },
}

impl ImageSource {
    fn new(image: &gltf::Image, base: &Path) -> Self {
        match image.source() {
            gltf::image::Source::View { view, .. } => ImageSource {
                name: image.name().map_or_else(|| format!("image {}", image.index()), str::to_string),
                location: ImageLocation::View {
                    buffer: view.buffer().index(),
                    offset: view.offset(),
                    length: view.length(),
                },
            },
            gltf::image::Source::Uri { uri, .. } => {
                let short = if uri.starts_with("data:") { "data URI" } else { uri };
                ImageSource {
                    name: image.name().unwrap_or(short).to_string(),
                    location: ImageLocation::Uri { uri: uri.to_string(), base: base.to_path_buf() },
                }
            }
        }
    }

    fn decode(&self, buffers: &[Vec<u8>]) -> Result<DecodedImage> {
        let bytes = match &self.location {
            ImageLocation::Uri { uri, base } => read_uri(uri, base)?,
            &ImageLocation::View { buffer, offset, length } => buffers
                .get(buffer)
                .and_then(|b| b.get(offset..offset.checked_add(length)?))
                .context("image bufferView is out of range of its buffer")?
                .to_vec(),
        };
        // The image crate converts every layout (grey, grey-alpha, RGB,
        // 16-bit) to RGBA8; glTF only allows PNG and JPEG.
        let image = image::load_from_memory(&bytes).context("cannot decode image")?.into_rgba8();
        Ok(DecodedImage { width: image.width(), height: image.height(), rgba8: image.into_raw() })
    }
}

/// Decodes `sources` on up to all available cores; the first failure (in
/// source order) is returned.
fn decode_parallel(sources: &[ImageSource], buffers: &[Vec<u8>]) -> Result<Vec<DecodedImage>> {
    let next = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(sources.len()).max(1);
    let mut results: Vec<(usize, Result<DecodedImage>)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(src) = sources.get(i) else { break out };
                        out.push((i, src.decode(buffers).with_context(|| format!("image '{}'", src.name))));
                    }
                })
            })
            .collect();
        workers.into_iter().flat_map(|w| w.join().unwrap_or_default()).collect()
    });
    ensure!(results.len() == sources.len(), "an image decoding thread panicked");
    results.sort_by_key(|(i, _)| *i);
    results.into_iter().map(|(_, r)| r).collect()
}

fn sampler_desc(s: &gltf::texture::Sampler) -> SamplerDesc {
    let wrap = |w: WrappingMode| match w {
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::Repeat => Wrap::Repeat,
    };
    let (min_filter, mipmaps) = match s.min_filter() {
        // No filter given: the renderer's choice, and mipmaps avoid aliasing.
        None => (Filter::Linear, true),
        Some(MinFilter::Nearest) => (Filter::Nearest, false),
        Some(MinFilter::Linear) => (Filter::Linear, false),
        Some(MinFilter::NearestMipmapNearest | MinFilter::NearestMipmapLinear) => (Filter::Nearest, true),
        Some(MinFilter::LinearMipmapNearest | MinFilter::LinearMipmapLinear) => (Filter::Linear, true),
    };
    SamplerDesc {
        mag_filter: match s.mag_filter() {
            Some(MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Linear,
        },
        min_filter,
        mipmaps,
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
    }
}

fn convert_material(m: &gltf::Material, slots: &mut TextureSlots) -> Material {
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
        transmission_texture,
        ior: m.ior().unwrap_or(1.5),
        casts_shadows: true,
        name,
    }
}

// ---------------------------------------------------------------------------
// Animations

const ANIMATION_INPUT: Expected =
    Expected { what: "animation input", dims: Dimensions::Scalar, types: &[DataType::F32], normalized: true };
const ANIMATION_VEC3: Expected =
    Expected { what: "animation output", dims: Dimensions::Vec3, types: &[DataType::F32], normalized: true };
const ANIMATION_ROTATION: Expected = Expected {
    what: "animation output",
    dims: Dimensions::Vec4,
    types: &[DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16],
    normalized: true,
};

/// Node animations; glTF node indices are the scene's node indices. Morph
/// target (`weights`) channels are skipped with a warning.
fn convert_animations(doc: &gltf::Document, buffers: &[Vec<u8>], path: &Path) -> Result<Vec<Animation>> {
    let mut animations = Vec::new();
    for anim in doc.animations() {
        let name = anim.name().map_or_else(|| format!("animation {}", anim.index()), str::to_string);
        let mut channels = Vec::new();
        for channel in anim.channels() {
            let context = || format!("animation '{name}' channel {}", channel.index());
            if channel.target().property() == gltf::animation::Property::MorphTargetWeights {
                log::warn!(
                    "{}: {}: morph target weights are not supported, channel skipped",
                    path.display(),
                    context()
                );
                continue;
            }
            channels.push(convert_channel(&channel, buffers).with_context(context)?);
        }
        animations.push(Animation::new(name, channels));
    }
    Ok(animations)
}

fn convert_channel(channel: &gltf::animation::Channel, buffers: &[Vec<u8>]) -> Result<AnimationChannel> {
    use gltf::animation::util::ReadOutputs;
    let sampler = channel.sampler();
    let interpolation = match sampler.interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let (input, output) = (sampler.input(), sampler.output());
    check_accessor(&input, &ANIMATION_INPUT, buffers)?;
    let rotation = channel.target().property() == gltf::animation::Property::Rotation;
    check_accessor(&output, if rotation { &ANIMATION_ROTATION } else { &ANIMATION_VEC3 }, buffers)?;
    ensure!(
        output.data_type() == DataType::F32 || output.normalized(),
        "animation output accessor {}: integer rotations must be normalized",
        output.index()
    );
    let reader = channel.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let times: Vec<f32> = reader.read_inputs().context("cannot read the animation input")?.collect();
    ensure!(
        times.len() == input.count(),
        "animation input: read {} of {} key times",
        times.len(),
        input.count()
    );
    let values = match reader.read_outputs().context("cannot read the animation output")? {
        ReadOutputs::Translations(it) => Channel::Translation(it.map(Vec3::from).collect()),
        ReadOutputs::Scales(it) => Channel::Scale(it.map(Vec3::from).collect()),
        ReadOutputs::Rotations(it) => Channel::Rotation(it.into_f32().map(Quat::from_array).collect()),
        ReadOutputs::MorphTargetWeights(_) => bail!("morph target weights are not supported"),
    };
    ensure!(
        values.len() == output.count(),
        "animation output: read {} of {} values",
        values.len(),
        output.count()
    );
    let finite = match &values {
        Channel::Translation(v) | Channel::Scale(v) => v.iter().all(|v| v.is_finite()),
        Channel::Rotation(v) => v.iter().all(|q| q.is_finite()),
    };
    ensure!(finite, "animation output has non-finite values");
    let channel = AnimationChannel { node: channel.target().node().index(), times, interpolation, values };
    channel.check()?;
    Ok(channel)
}

// ---------------------------------------------------------------------------
// Nodes, cameras, lights

fn build_nodes(doc: &gltf::Document, scene: &mut Scene) -> Result<()> {
    for node in doc.nodes() {
        let name = node.name().map_or_else(|| format!("node {}", node.index()), str::to_string);
        let local = local_transform(node.transform()).with_context(|| format!("node '{name}'"))?;
        let children = node.children().map(|c| c.index()).collect();
        scene.nodes.push(Node { name, local, children, ..Default::default() });
    }
    link_parents(scene)?;
    scene.roots = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => (0..scene.nodes.len()).filter(|&i| scene.nodes[i].parent.is_none()).collect(),
    };
    let reachable = reachable_nodes(scene);
    let world = scene.world_matrices();
    for node in doc.nodes().filter(|n| reachable[n.index()]) {
        attach_node_content(&node, &world[node.index()], scene);
    }
    Ok(())
}

/// glTF skins, and the joint indices of every skinned node's mesh checked
/// against its skin (an out-of-range joint would read past the joint
/// matrices on the GPU).
fn convert_skins(doc: &gltf::Document, buffers: &[Vec<u8>], scene: &mut Scene) -> Result<()> {
    for skin in doc.skins() {
        let name = skin.name().map_or_else(|| format!("skin {}", skin.index()), str::to_string);
        let context = || format!("skin '{name}'");
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        ensure!(!joints.is_empty(), "{}: has no joints", context());
        let inverse_bind = match skin.inverse_bind_matrices() {
            Some(acc) => {
                const IBM: Expected = Expected {
                    what: "inverseBindMatrices",
                    dims: Dimensions::Mat4,
                    types: &[DataType::F32],
                    normalized: true,
                };
                check_accessor(&acc, &IBM, buffers).with_context(context)?;
                ensure!(
                    acc.count() >= joints.len(),
                    "{}: {} inverse bind matrices for {} joints",
                    context(),
                    acc.count(),
                    joints.len()
                );
                let reader = skin.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
                let m: Vec<Mat4> = reader
                    .read_inverse_bind_matrices()
                    .with_context(|| format!("{}: cannot read inverseBindMatrices", context()))?
                    .map(|m| Mat4::from_cols_array_2d(&m))
                    .collect();
                ensure!(m.iter().all(|m| m.is_finite()), "{}: non-finite inverse bind matrix", context());
                m
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        scene.skins.push(Skin { name, joints, inverse_bind });
    }
    for node in doc.nodes() {
        let (Some(skin), Some(mesh)) = (node.skin(), node.mesh()) else { continue };
        let n = node.index();
        scene.nodes[n].skin = Some(skin.index());
        let s = &scene.skins[skin.index()];
        let m = &scene.meshes[mesh.index()];
        for (p, prim) in m.primitives.iter().enumerate() {
            let Some(max) = prim.skin.as_ref().and_then(SkinWeights::max_joint) else { continue };
            ensure!(
                (max as usize) < s.joints.len(),
                "node '{}': mesh '{}' primitive {p} uses joint {max} but skin '{}' has {} joints",
                scene.nodes[n].name,
                m.name,
                s.name,
                s.joints.len()
            );
        }
    }
    Ok(())
}

/// Local TRS from either glTF form; matrices are decomposed (shear is lost,
/// which glTF forbids anyway).
fn local_transform(t: gltf::scene::Transform) -> Result<Transform> {
    let (translation, rotation, scale) = match t {
        gltf::scene::Transform::Matrix { matrix } => {
            let (s, r, t) = Mat4::from_cols_array_2d(&matrix).to_scale_rotation_translation();
            (t, r, s)
        }
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            (Vec3::from(translation), Quat::from_array(rotation), Vec3::from(scale))
        }
    };
    let length = rotation.length();
    let rotation = (length.is_finite() && length > 1e-6).then(|| rotation / length);
    let rotation = match rotation {
        Some(r) => r,
        // A zero-scale matrix has no recoverable rotation; it draws nothing anyway.
        None if scale.cmpeq(Vec3::ZERO).any() => Quat::IDENTITY,
        None => bail!("has a non-finite or zero rotation"),
    };
    ensure!(translation.is_finite() && scale.is_finite(), "has a non-finite transform");
    Ok(Transform { translation, rotation, scale })
}

/// Sets `parent` from the children lists, rejecting the malformed
/// hierarchies (shared children, cycles) the crate's validation lets through.
fn link_parents(scene: &mut Scene) -> Result<()> {
    for p in 0..scene.nodes.len() {
        for c in scene.nodes[p].children.clone() {
            let child = scene.nodes.get_mut(c).with_context(|| format!("node {p} has no child {c}"))?;
            ensure!(child.parent.is_none(), "node '{}' has more than one parent", child.name);
            child.parent = Some(p);
        }
    }
    for start in 0..scene.nodes.len() {
        let (mut at, mut steps) = (start, 0);
        while let Some(p) = scene.nodes[at].parent {
            at = p;
            steps += 1;
            ensure!(steps <= scene.nodes.len(), "node '{}' is its own ancestor", scene.nodes[start].name);
        }
    }
    Ok(())
}

fn reachable_nodes(scene: &Scene) -> Vec<bool> {
    let mut seen = vec![false; scene.nodes.len()];
    let mut stack: Vec<usize> = scene.roots.clone();
    while let Some(i) = stack.pop() {
        if let Some(s) = seen.get_mut(i).filter(|s| !**s) {
            *s = true;
            stack.extend(&scene.nodes[i].children);
        }
    }
    seen
}

/// Mesh (as its own object), camera and light of one node of the drawn scene.
fn attach_node_content(node: &gltf::Node, world: &Mat4, scene: &mut Scene) {
    let i = node.index();
    if let Some(mesh) = node.mesh() {
        let name = node.name().or(mesh.name()).map_or_else(|| format!("node {i}"), str::to_string);
        scene.nodes[i].mesh = Some(mesh.index());
        scene.nodes[i].object = Some(scene.objects.len());
        scene.objects.push(Object { name, props: Default::default() });
    }
    if let Some(cam) = node.camera() {
        scene.nodes[i].camera = Some(scene.cameras.len());
        scene.cameras.push(convert_camera(&cam, &scene.nodes[i].name, world));
    }
    if let Some(light) = node.light() {
        scene.lights.push(convert_light(&light, &scene.nodes[i].name, world, i));
    }
}

fn convert_camera(cam: &gltf::Camera, node_name: &str, world: &Mat4) -> Camera {
    let name = cam.name().unwrap_or(node_name).to_string();
    let (yfov, znear) = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => (p.yfov(), p.znear()),
        gltf::camera::Projection::Orthographic(o) => {
            // Approximated by a perspective that frames ymag half-height at
            // the middle of the ortho depth range.
            let depth = (0.5 * (o.znear() + o.zfar())).max(1e-3);
            log::warn!("camera '{name}' is orthographic: approximating it with a perspective camera");
            (2.0 * (o.ymag().abs() / depth).atan(), o.znear().max(depth * 1e-3))
        }
    };
    let yfov = if yfov.is_finite() { yfov.clamp(1f32.to_radians(), 170f32.to_radians()) } else { 1.0 };
    let znear = if znear.is_finite() && znear > 0.0 { znear } else { 0.01 };
    Camera { name, world: *world, yfov, znear }
}

fn convert_light(
    light: &gltf::khr_lights_punctual::Light,
    node_name: &str,
    world: &Mat4,
    node: usize,
) -> Light {
    use gltf::khr_lights_punctual::Kind;
    let kind = match light.kind() {
        Kind::Directional => LightKind::Directional,
        Kind::Point => LightKind::Point,
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            LightKind::Spot { inner_cone: inner_cone_angle, outer_cone: outer_cone_angle }
        }
    };
    Light {
        name: light.name().unwrap_or(node_name).to_string(),
        kind,
        color: Vec3::from(light.color()),
        intensity: light.intensity(),
        position: world.transform_point3(Vec3::ZERO),
        // Lights shine down their node's -Z.
        direction: world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z),
        range: light.range(),
        casts_shadows: true,
        node: Some(node),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shared(relative: &str) -> PathBuf {
        let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/assets")).join(relative);
        assert!(
            path.exists(),
            "missing shared test asset {} (CI keeps ../shared beside the checkout)",
            path.display()
        );
        path
    }

    /// An empty scratch directory for one test.
    fn temp_dir(test: &str) -> PathBuf {
        // One fixed folder per test, emptied first: reruns do not pile up temp dirs.
        let dir = std::env::temp_dir().join("hybrid-rt-tests").join(format!("gltf-{test}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("cannot create a temp dir");
        dir
    }

    fn base64(bytes: &[u8]) -> String {
        const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let n = chunk.iter().enumerate().fold(0u32, |n, (i, &b)| n | (b as u32) << (16 - 8 * i));
            for i in 0..4 {
                let c =
                    if i <= chunk.len() { ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char } else { '=' };
                out.push(c);
            }
        }
        out
    }

    /// 36 bytes of positions, 6 bytes of u16 indices (+2 padding), then 24
    /// bytes of UVs equal to the positions' xy.
    fn triangle_bin(positions: [[f32; 3]; 3], indices: [u16; 3]) -> Vec<u8> {
        let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
        bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
        bin.extend([0, 0]);
        bin.extend(TRIANGLE.iter().flat_map(|p| p[..2].to_vec()).flat_map(|f| f.to_le_bytes()));
        bin
    }

    const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    /// One indexed triangle mesh "tri" reading buffer `uri`; `extra` adds
    /// top-level members (materials, textures, ...) and `material` makes the
    /// primitive use material 0.
    fn triangle_json(uri: &str, index_count: u32, material: bool, extra: &str) -> String {
        let material = if material { r#", "material": 0"# } else { "" };
        format!(
            r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "name": "tri node"}}],
  "meshes": [{{"name": "tri", "primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 2}}, "indices": 1{material}}}]}}],
  "buffers": [{{"uri": "{uri}", "byteLength": 68}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 6}},
    {{"buffer": 0, "byteOffset": 44, "byteLength": 24}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": {index_count}, "type": "SCALAR"}},
    {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}}
  ]{extra}
}}"#
        )
    }

    /// Writes `tri.gltf` + `tri.bin` and returns the .gltf path.
    fn write_triangle(dir: &Path, bin: &[u8], json: &str) -> PathBuf {
        std::fs::write(dir.join("tri.bin"), bin).unwrap();
        let path = dir.join("tri.gltf");
        std::fs::write(&path, json).unwrap();
        path
    }

    fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
        let mut json = json.as_bytes().to_vec();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = bin.to_vec();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend(b"glTF");
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(json);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
        out
    }

    fn error_of(path: &Path) -> String {
        match load(path) {
            Ok(_) => panic!("{} loaded but should have failed", path.display()),
            Err(e) => format!("{e:#}"),
        }
    }

    fn assert_orthonormal_frame(v: &Vertex) {
        let n = Vec3::from(v.normal);
        let t = Vec3::from_slice(&v.tangent[..3]);
        assert!((n.length() - 1.0).abs() < 1e-3 && (t.length() - 1.0).abs() < 1e-3, "{v:?}");
        assert!(n.dot(t).abs() < 1e-3, "{v:?}");
        assert_eq!(v.tangent[3].abs(), 1.0);
    }

    #[test]
    fn khronos_triangle_gets_flat_normals_and_a_default_material() {
        let scene = load(&shared("gltf/Triangle/glTF/Triangle.gltf")).unwrap();
        assert_eq!(scene.meshes.len(), 1);
        let p = &scene.meshes[0].primitives[0];
        assert_eq!(p.indices, vec![0, 1, 2]);
        assert!(p.vertices.iter().all(|v| v.normal == [0.0, 0.0, 1.0] && v.uv == [0.0, 0.0]));
        assert!(p.vertices.iter().all(|v| v.tangent[3] == 1.0), "fallback tangents have w = 1");
        p.vertices.iter().for_each(assert_orthonormal_frame);
        assert_eq!(scene.materials.len(), 1, "the default material is appended");
        assert_eq!(p.material, 0);
        assert_eq!(scene.objects.len(), 1);
        assert_eq!(scene.nodes[0].object, Some(0));
        assert_eq!(scene.roots, vec![0]);
        assert_eq!(p.bounds.max, Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn embedded_and_external_buffers_match() {
        let external = load(&shared("gltf/Triangle/glTF/Triangle.gltf")).unwrap();
        let embedded = load(&shared("gltf/Triangle/glTF-Embedded/Triangle.gltf")).unwrap();
        let (a, b) = (&external.meshes[0].primitives[0], &embedded.meshes[0].primitives[0]);
        assert_eq!(a.vertices, b.vertices);
        assert_eq!(a.indices, b.indices);
    }

    #[test]
    fn non_indexed_triangle_gets_sequential_indices() {
        let scene = load(&shared("gltf/TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf")).unwrap();
        assert_eq!(scene.meshes[0].primitives[0].indices, vec![0, 1, 2]);
    }

    #[test]
    fn damaged_helmet_textures_and_generated_tangents() {
        let scene = load(&shared("gltf/DamagedHelmet/glTF/DamagedHelmet.gltf")).unwrap();
        let p = &scene.meshes[0].primitives[0];
        let m = &scene.materials[p.material];
        let tex = |r: Option<TextureRef>| &scene.textures[r.expect("texture slot is empty").texture];
        assert!(tex(m.base_color_texture).srgb);
        assert!(tex(m.emissive_texture).srgb);
        assert!(!tex(m.normal_texture).srgb);
        assert!(!tex(m.metallic_roughness_texture).srgb);
        assert!(!tex(m.occlusion_texture).srgb);
        assert_eq!(scene.textures.len(), 5);
        for t in &scene.textures {
            assert_eq!(t.rgba8.len(), (t.width * t.height * 4) as usize);
        }
        assert!(m.emissive.iter().all(|&e| e > 0.0));
        // The file has no TANGENT attribute: they must have been generated.
        p.vertices.iter().for_each(assert_orthonormal_frame);
        let distinct: std::collections::HashSet<[u32; 3]> = p
            .vertices
            .iter()
            .map(|v| v.tangent[..3].iter().map(|f| f.to_bits()).collect::<Vec<_>>().try_into().unwrap())
            .collect();
        assert!(distinct.len() > 100, "tangents look like a constant fallback");
    }

    #[test]
    fn sponza_is_large_and_instanced() {
        let scene = Scene::load(&shared("scenes/SponzaCapsaicin/Sponza.gltf")).unwrap();
        assert!(scene.triangle_count() > 100_000, "{} triangles", scene.triangle_count());
        assert_eq!(scene.objects.len(), scene.nodes.iter().filter(|n| n.mesh.is_some()).count());
        assert!(scene.textures.len() >= 49);
        assert!(scene.materials.iter().any(|m| m.alpha_mode == AlphaMode::Blend));
        // Normal-mapped primitives had no TANGENT attribute: generated ones.
        let mapped = scene.meshes.iter().flat_map(|m| &m.primitives);
        let mapped = mapped.filter(|p| scene.materials[p.material].normal_texture.is_some());
        mapped.flat_map(|p| &p.vertices).step_by(97).for_each(assert_orthonormal_frame);
        let extent = scene.bounds.extent();
        assert!(extent.x > 20.0 && extent.y > 10.0, "Sponza bounds {:?}", scene.bounds);
    }

    #[test]
    fn lights_and_cameras_are_placed_in_world_space() {
        let dir = temp_dir("lights");
        let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
        let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
        let json = triangle_json(&uri, 3, false, "").replace(
            r#""nodes": [{"mesh": 0, "name": "tri node"}],"#,
            r#""nodes": [
                {"mesh": 0, "name": "tri node", "children": [1, 2, 3]},
                {"name": "lamp", "translation": [0, 2, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                {"name": "spot", "translation": [1, 0, 0], "rotation": [-0.7071068, 0, 0, 0.7071068],
                 "extensions": {"KHR_lights_punctual": {"light": 1}}},
                {"name": "eye", "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1], "camera": 0}
            ],
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "point", "color": [1, 0.5, 0.25], "intensity": 20, "range": 8},
                {"type": "spot", "name": "beam", "intensity": 5, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}
            ]}},
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],"#,
        );
        let path = dir.join("lights.gltf");
        std::fs::write(&path, json).unwrap();
        let mut scene = load(&path).unwrap();
        // Moving the root must move its children's world transforms.
        scene.nodes[0].local.translation = Vec3::new(10.0, 0.0, 0.0);
        assert_eq!(scene.lights.len(), 2);
        let point = &scene.lights[0];
        assert_eq!(point.kind, LightKind::Point);
        assert_eq!(point.position, Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(point.color, Vec3::new(1.0, 0.5, 0.25));
        assert_eq!((point.intensity, point.range, point.node), (20.0, Some(8.0), Some(1)));
        let spot = &scene.lights[1];
        assert_eq!(spot.name, "beam");
        assert_eq!(spot.kind, LightKind::Spot { inner_cone: 0.2, outer_cone: 0.5 });
        // -90 degrees about X turns the spot's -Z into -Y.
        assert!((spot.direction - Vec3::NEG_Y).length() < 1e-5, "{}", spot.direction);
        assert_eq!(spot.position, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(scene.cameras.len(), 1);
        let cam = &scene.cameras[0];
        assert_eq!((cam.yfov, cam.znear), (0.8, 0.1));
        assert_eq!(cam.position(), Vec3::new(0.0, 0.0, 5.0));
        assert_eq!(scene.nodes[3].camera, Some(0));
        assert_eq!(scene.nodes[3].parent, Some(0));
        assert_eq!(scene.world_matrices()[3].w_axis.truncate(), Vec3::new(10.0, 0.0, 5.0));
    }

    #[test]
    fn textures_are_deduplicated_per_image_sampler_and_colour_space() {
        let dir = temp_dir("textures");
        // A 16-bit greyscale PNG exercises the format conversion to RGBA8.
        let grey =
            image::ImageBuffer::<image::Luma<u16>, _>::from_fn(2, 2, |x, _| image::Luma([x as u16 * 65535]));
        grey.save(dir.join("grey.png")).unwrap();
        let extra = r#",
  "materials": [
    {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 0}},
     "emissiveTexture": {"index": 1}, "normalTexture": {"index": 0, "scale": 0.5}}
  ],
  "samplers": [{"magFilter": 9728, "minFilter": 9729, "wrapS": 33071, "wrapT": 33648}],
  "textures": [{"source": 0, "sampler": 0}, {"source": 0, "sampler": 0}],
  "images": [{"uri": "grey.png"}]"#;
        let path = write_triangle(
            &dir,
            &triangle_bin(TRIANGLE, [0, 1, 2]),
            &triangle_json("tri.bin", 3, true, extra),
        );
        let scene = load(&path).unwrap();
        // (grey, sampler, sRGB) for base colour and emissive; (grey, sampler, linear) for the rest.
        assert_eq!(scene.textures.len(), 2);
        let m = &scene.materials[0];
        assert_eq!(m.base_color_texture, m.emissive_texture);
        assert_eq!(m.metallic_roughness_texture, m.normal_texture);
        assert_ne!(m.base_color_texture, m.normal_texture);
        assert_eq!(m.normal_scale, 0.5);
        let t = &scene.textures[0];
        assert_eq!(t.rgba8, vec![0, 0, 0, 255, 255, 255, 255, 255, 0, 0, 0, 255, 255, 255, 255, 255]);
        assert_eq!(
            t.sampler,
            SamplerDesc {
                mag_filter: Filter::Nearest,
                min_filter: Filter::Linear,
                mipmaps: false,
                wrap_u: Wrap::ClampToEdge,
                wrap_v: Wrap::MirroredRepeat
            }
        );
        // A normal-mapped material without TANGENT gets generated tangents.
        let p = &scene.meshes[0].primitives[0];
        assert!(p.vertices.iter().all(|v| v.tangent == [1.0, 0.0, 0.0, 1.0]), "{:?}", p.vertices);
    }

    #[test]
    fn strips_and_fans_become_lists() {
        assert_eq!(triangle_list(Mode::TriangleStrip, vec![0, 1, 2, 3, 4]), vec![0, 1, 2, 1, 3, 2, 2, 3, 4]);
        assert_eq!(triangle_list(Mode::TriangleFan, vec![0, 1, 2, 3]), vec![1, 2, 0, 2, 3, 0]);
        assert_eq!(triangle_list(Mode::Triangles, vec![0, 1, 2, 3]), vec![0, 1, 2]);
    }

    #[test]
    fn glb_loads_and_truncated_glb_fails() {
        let dir = temp_dir("glb");
        let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
        let json = triangle_json("", 3, false, "").replace(r#""uri": "", "#, "");
        let bytes = glb(&json, &bin);
        let path = dir.join("tri.glb");
        std::fs::write(&path, &bytes).unwrap();
        let scene = load(&path).unwrap();
        assert_eq!(scene.meshes[0].primitives[0].indices, vec![0, 1, 2]);
        for cut in [bytes.len() - 10, 30, 14] {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            let err = error_of(&path);
            assert!(err.contains("tri.glb") && err.contains("truncated"), "{err}");
        }
    }

    #[test]
    fn missing_files_are_named() {
        let err = error_of(Path::new("/nonexistent/scene.gltf"));
        assert!(err.contains("/nonexistent/scene.gltf"), "{err}");

        let dir = temp_dir("missing");
        let path = dir.join("tri.gltf");
        std::fs::write(&path, triangle_json("absent.bin", 3, false, "")).unwrap();
        let err = error_of(&path);
        assert!(err.contains("tri.gltf") && err.contains("buffer 0") && err.contains("absent.bin"), "{err}");

        let extra = r#",
  "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}],
  "images": [{"uri": "no%20such.png"}]"#;
        let path = write_triangle(
            &dir,
            &triangle_bin(TRIANGLE, [0, 1, 2]),
            &triangle_json("tri.bin", 3, true, extra),
        );
        let err = error_of(&path);
        assert!(err.contains("tri.gltf") && err.contains("no such.png"), "{err}");
    }

    /// SimpleSkin with its JSON edited by `edit`, beside copies of its buffers.
    fn edited_simple_skin(test: &str, edit: impl Fn(&str) -> String) -> PathBuf {
        let src = shared("gltf/SimpleSkin/glTF");
        let dir = temp_dir(test);
        for f in ["skinGeometry.bin", "skinningData.bin", "inverseBindMatrices.bin", "skinAnimation.bin"] {
            std::fs::copy(src.join(f), dir.join(f)).unwrap();
        }
        let json = std::fs::read_to_string(src.join("SimpleSkin.gltf")).unwrap();
        let path = dir.join("SimpleSkin.gltf");
        std::fs::write(&path, edit(&json)).unwrap();
        path
    }

    #[test]
    fn skins_and_weights_are_imported() {
        let mut scene = load(&shared("gltf/SimpleSkin/glTF/SimpleSkin.gltf")).unwrap();
        scene.update_world();
        assert_eq!(scene.skins.len(), 1);
        assert_eq!(scene.skins[0].joints, vec![1, 2]);
        assert_eq!(scene.nodes[0].skin, Some(0));
        let w = scene.meshes[0].primitives[0].skin.as_ref().expect("JOINTS_0/WEIGHTS_0 read");
        assert_eq!(w.joints.len(), scene.meshes[0].primitives[0].vertices.len());
        for ws in &w.weights {
            assert!((ws.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        }
        let inst = &scene.instances[0];
        assert_eq!(inst.skinned, Some(0));
        for model in [
            "gltf/Fox/glTF/Fox.gltf",
            "gltf/CesiumMan/glTF/CesiumMan.gltf",
            "gltf/RiggedFigure/glTF/RiggedFigure.gltf",
        ] {
            let mut s = load(&shared(model)).unwrap();
            s.update_world();
            assert!(s.instances.iter().any(|i| i.skinned.is_some()), "{model}: nothing skinned");
        }
    }

    #[test]
    fn out_of_range_joint_is_rejected() {
        // Only one joint left while the weights still reference joint 1.
        let path =
            edited_simple_skin("bad-joint", |j| j.replace("\"joints\" : [ 1, 2 ]", "\"joints\" : [ 1 ]"));
        let err = error_of(&path);
        assert!(err.contains("uses joint 1") && err.contains("has 1 joints"), "{err}");
        assert!(err.contains("SimpleSkin.gltf"), "{err}");
    }

    #[test]
    fn joints_without_weights_are_rejected() {
        let path = edited_simple_skin("no-weights", |j| j.replace(",\n        \"WEIGHTS_0\" : 3", ""));
        let err = error_of(&path);
        assert!(err.contains("JOINTS_0 but no WEIGHTS_0"), "{err}");
    }

    #[test]
    fn non_finite_position_is_rejected() {
        let dir = temp_dir("nan");
        let mut positions = TRIANGLE;
        positions[1][2] = f32::NAN;
        let path = write_triangle(
            &dir,
            &triangle_bin(positions, [0, 1, 2]),
            &triangle_json("tri.bin", 3, false, ""),
        );
        let err = error_of(&path);
        assert!(
            err.contains("tri.gltf: mesh 'tri' primitive 0: vertex 1 has a non-finite position"),
            "{err}"
        );
    }

    #[test]
    fn out_of_range_index_is_rejected() {
        let dir = temp_dir("index");
        let path =
            write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 7]), &triangle_json("tri.bin", 3, false, ""));
        let err = error_of(&path);
        assert!(err.contains("mesh 'tri' primitive 0") && err.contains("index 7"), "{err}");
    }

    #[test]
    fn accessor_outside_its_buffer_view_is_rejected() {
        let dir = temp_dir("accessor");
        let path = write_triangle(
            &dir,
            &triangle_bin(TRIANGLE, [0, 1, 2]),
            &triangle_json("tri.bin", 30, false, ""),
        );
        let err = error_of(&path);
        assert!(
            err.contains("tri.gltf") && err.contains("indices accessor 1") && err.contains("out of range"),
            "{err}"
        );
    }

    #[test]
    fn corrupted_glb_bytes_never_panic() {
        let dir = temp_dir("corrupt");
        let json = triangle_json("", 3, false, "").replace(r#""uri": "", "#, "");
        let bytes = glb(&json, &triangle_bin(TRIANGLE, [0, 1, 2]));
        let path = dir.join("tri.glb");
        for i in 0..bytes.len() {
            for value in [0x00, 0x39, 0xff] {
                let mut corrupt = bytes.clone();
                corrupt[i] = value;
                std::fs::write(&path, &corrupt).unwrap();
                // Errors are fine; a panic fails the test.
                let _ = load(&path);
            }
        }
    }

    #[test]
    fn odd_numbers_in_the_json_never_panic() {
        let dir = temp_dir("numbers");
        let extra = r#",
  "materials": [{"normalTexture": {"index": 0, "texCoord": 0}}],
  "textures": [{"source": 0, "sampler": 0}],
  "samplers": [{"minFilter": 9729, "wrapS": 10497}],
  "images": [{"bufferView": 2, "mimeType": "image/png"}]"#;
        let json = triangle_json("tri.bin", 3, true, extra);
        let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
        // Every run of digits, in turn, replaced by edge-case values.
        let runs: Vec<(usize, usize)> = json
            .char_indices()
            .filter(|&(i, c)| c.is_ascii_digit() && !json[..i].ends_with(|p: char| p.is_ascii_digit()))
            .map(|(i, _)| (i, json[i..].find(|c: char| !c.is_ascii_digit()).map_or(json.len(), |n| i + n)))
            .collect();
        assert!(runs.len() > 40);
        for (start, end) in runs {
            for value in ["0", "1", "2", "7", "65535", "4294967295", "18446744073709551615", "1e30"] {
                let mutated = format!("{}{value}{}", &json[..start], &json[end..]);
                let path = write_triangle(&dir, &bin, &mutated);
                // Errors are fine; a panic fails the test.
                let _ = load(&path);
            }
        }
    }

    #[test]
    fn dangling_light_reference_is_an_error() {
        let dir = temp_dir("dangling");
        let json = triangle_json("tri.bin", 3, false, "").replace(
            r#"{"mesh": 0, "name": "tri node"}"#,
            r#"{"mesh": 0, "name": "tri node", "extensions": {"KHR_lights_punctual": {"light": 3}}}"#,
        );
        let path = write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &json);
        let err = error_of(&path);
        assert!(err.contains("tri.gltf") && err.contains("light"), "{err}");
    }

    /// The triangle plus a SCALAR accessor 3 over the UVs (0, 0, 1) for key
    /// times and an animation 'slide' whose channels are `channels`.
    fn animated_triangle(dir: &Path, channels: &str, samplers: &str) -> PathBuf {
        let extra = format!(
            r#", "animations": [{{"name": "slide", "channels": [{channels}], "samplers": [{samplers}]}}]"#
        );
        let json = triangle_json("tri.bin", 3, false, &extra).replace(
            r#""count": 3, "type": "VEC2"}"#,
            r#""count": 3, "type": "VEC2"}, {"bufferView": 2, "componentType": 5126, "count": 3, "type": "SCALAR"}"#,
        );
        write_triangle(dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &json)
    }

    #[test]
    fn animations_are_imported_and_morph_channels_skipped() {
        use crate::scene::animation::{Channel, Interpolation};
        let dir = temp_dir("animation");
        let path = animated_triangle(
            &dir,
            r#"{"sampler": 0, "target": {"node": 0, "path": "translation"}},
               {"sampler": 1, "target": {"node": 0, "path": "weights"}}"#,
            r#"{"input": 3, "output": 0, "interpolation": "STEP"}, {"input": 3, "output": 3}"#,
        );
        let mut scene = load(&path).unwrap();
        assert_eq!(scene.animations.len(), 1);
        let a = &scene.animations[0];
        assert_eq!((a.name.as_str(), a.duration, a.channels.len()), ("slide", 1.0, 1));
        let c = &a.channels[0];
        assert_eq!((c.node, c.interpolation, &c.times), (0, Interpolation::Step, &vec![0.0, 0.0, 1.0]));
        assert_eq!(c.values, Channel::Translation(TRIANGLE.iter().map(|&p| Vec3::from(p)).collect()));
        scene.animate(0, 0.5);
        assert_eq!(scene.nodes[0].local.translation, Vec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn malformed_animations_are_reported_with_the_file_and_channel() {
        let dir = temp_dir("bad-animation");
        let translation = r#"{"sampler": 0, "target": {"node": 0, "path": "translation"}}"#;
        let rotation = r#"{"sampler": 0, "target": {"node": 0, "path": "rotation"}}"#;
        let cases = [
            // VEC2 output for a translation.
            (translation, r#"{"input": 3, "output": 2}"#, "animation output accessor 2"),
            // Three values for three keys is not enough for a cubic spline.
            (translation, r#"{"input": 3, "output": 0, "interpolation": "CUBICSPLINE"}"#, "needs 9"),
            // VEC3 output for a rotation.
            (rotation, r#"{"input": 3, "output": 0}"#, "Vec4"),
            // VEC3 key times.
            (translation, r#"{"input": 0, "output": 0}"#, "animation input accessor 0"),
        ];
        for (channel, sampler, expected) in cases {
            let path = animated_triangle(&dir, channel, sampler);
            let err = error_of(&path);
            assert!(
                err.contains("tri.gltf")
                    && err.contains("animation 'slide' channel 0")
                    && err.contains(expected),
                "{sampler}: {err}"
            );
        }
        // Out-of-range accessor, sampler and node references never panic.
        for (channel, sampler) in [
            (translation, r#"{"input": 9, "output": 0}"#),
            (
                r#"{"sampler": 4, "target": {"node": 0, "path": "translation"}}"#,
                r#"{"input": 3, "output": 0}"#,
            ),
            (
                r#"{"sampler": 0, "target": {"node": 7, "path": "translation"}}"#,
                r#"{"input": 3, "output": 0}"#,
            ),
            (r#"{"sampler": 0, "target": {"node": 0, "path": "colour"}}"#, r#"{"input": 3, "output": 0}"#),
        ] {
            let err = error_of(&animated_triangle(&dir, channel, sampler));
            assert!(err.contains("tri.gltf"), "{err}");
        }
        // Every number of a valid animation, in turn, replaced by edge cases.
        let (channel, sampler) = (rotation, r#"{"input": 3, "output": 0, "interpolation": "CUBICSPLINE"}"#);
        let text = format!("{channel}|{sampler}");
        for (i, _) in text.char_indices().filter(|(_, c)| c.is_ascii_digit()) {
            for value in ["1", "2", "4", "9", "4294967295"] {
                let mutated = format!("{}{value}{}", &text[..i], &text[i + 1..]);
                let (c, s) = mutated.split_once('|').unwrap();
                // Errors are fine; a panic fails the test.
                let _ = load(&animated_triangle(&dir, c, s));
            }
        }
    }

    #[test]
    fn invalid_json_references_are_reported_with_the_file() {
        let dir = temp_dir("invalid");
        let json = triangle_json("tri.bin", 3, false, "").replace(r#""indices": 1"#, r#""indices": 9"#);
        let path = write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &json);
        let err = error_of(&path);
        assert!(err.contains("tri.gltf") && err.contains("indices"), "{err}");
    }
}
