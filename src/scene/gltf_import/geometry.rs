//! Meshes: primitives with their attributes (POSITION, NORMAL, TEXCOORD_0,
//! TANGENT, JOINTS_0/WEIGHTS_0) and indices read and checked, strips and
//! fans turned into lists, and normals and tangents repaired or generated.

use anyhow::{bail, ensure, Context, Result};
use glam::{Vec2, Vec3, Vec4};
use gltf::mesh::Mode;

use super::checks::{
    check_accessor, Expected, INDICES, JOINTS_0, NORMAL, POSITION, TANGENT, TEXCOORD_0, WEIGHTS_0,
};
use crate::scene::skin::SkinWeights;
use crate::scene::tangents::{
    bounds_of, fallback_tangent, fill_fallback_tangents, flatten_with_face_normals, generate_tangents,
    smooth_normals,
};
use crate::scene::{Mesh, Primitive, Vertex};

pub(super) fn convert_mesh(
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
pub(super) fn triangle_list(mode: Mode, indices: Vec<u32>) -> Vec<u32> {
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
