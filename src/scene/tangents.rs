//! Vertex-attribute generation shared by the loaders: normals when a mesh has
//! none, and tangents following glTF's MikkTSpace convention
//! (T along +u, bitangent B = cross(N, T) * w pointing along +v).

use glam::{Vec2, Vec3, Vec4};

use super::{Aabb, Vertex};

/// Tangents from UV derivatives, accumulated per vertex (area-weighted, since
/// the unnormalised per-triangle vectors scale with triangle size), then
/// Gram-Schmidt orthogonalised against the vertex normal. `w` is the
/// handedness sign, -1 where the UVs are mirrored. Vertices whose triangles
/// all have degenerate UVs get an arbitrary orthogonal tangent with w = 1.
/// Indices must be in range (the loaders check them before calling this).
pub fn generate_tangents(vertices: &mut [Vertex], indices: &[u32]) {
    let mut tan = vec![Vec3::ZERO; vertices.len()];
    let mut bitan = vec![Vec3::ZERO; vertices.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        let Some((t, bt)) = triangle_tangent(&vertices[a], &vertices[b], &vertices[c]) else {
            continue;
        };
        for i in [a, b, c] {
            tan[i] += t;
            bitan[i] += bt;
        }
    }
    for (v, (t, b)) in vertices.iter_mut().zip(tan.into_iter().zip(bitan)) {
        v.tangent = orthonormal_tangent(Vec3::from(v.normal), t, b).to_array();
    }
}

/// Unit dP/du and dP/dv of one triangle, weighted by its area so large
/// triangles dominate a shared vertex; None when the UV mapping is
/// degenerate (zero UV area) or the result is not finite.
fn triangle_tangent(v0: &Vertex, v1: &Vertex, v2: &Vertex) -> Option<(Vec3, Vec3)> {
    let p0 = Vec3::from(v0.position);
    let e1 = Vec3::from(v1.position) - p0;
    let e2 = Vec3::from(v2.position) - p0;
    let uv0 = Vec2::from(v0.uv);
    let d1 = Vec2::from(v1.uv) - uv0;
    let d2 = Vec2::from(v2.uv) - uv0;
    let det = d1.x * d2.y - d2.x * d1.y;
    if det.abs() < 1e-20 || !det.is_finite() {
        return None;
    }
    let t = ((e1 * d2.y - e2 * d1.y) / det).try_normalize()?;
    let b = ((e2 * d1.x - e1 * d2.x) / det).try_normalize()?;
    let area = e1.cross(e2).length();
    area.is_finite().then_some((t * area, b * area))
}

/// Gram-Schmidt of the accumulated tangent against `n`, with the handedness
/// taken from the accumulated bitangent.
fn orthonormal_tangent(n: Vec3, t: Vec3, b: Vec3) -> Vec4 {
    let n = n.try_normalize().unwrap_or(Vec3::Z);
    let Some(t_ortho) = (t - n * n.dot(t)).try_normalize() else {
        return fallback_tangent(n);
    };
    let w = if n.cross(t_ortho).dot(b) < 0.0 { -1.0 } else { 1.0 };
    t_ortho.extend(w)
}

/// Any unit vector orthogonal to `n`, w = 1: for surfaces without a normal
/// map the shader only needs a valid frame.
pub fn fallback_tangent(n: Vec3) -> Vec4 {
    let n = n.try_normalize().unwrap_or(Vec3::Z);
    // Cross with the axis least aligned with n for the best conditioning.
    let a = n.abs();
    let axis = if a.x <= a.y && a.x <= a.z {
        Vec3::X
    } else if a.y <= a.z {
        Vec3::Y
    } else {
        Vec3::Z
    };
    n.cross(axis).normalize().extend(1.0)
}

/// Fills every vertex's tangent with `fallback_tangent` of its normal.
pub fn fill_fallback_tangents(vertices: &mut [Vertex]) {
    for v in vertices {
        v.tangent = fallback_tangent(Vec3::from(v.normal)).to_array();
    }
}

/// Un-shares vertices so every triangle has its own three and gives them the
/// face normal: glTF requires flat normals when a primitive has none.
/// Degenerate triangles get +Y (any unit vector works, they cover no pixels).
pub fn flatten_with_face_normals(vertices: &[Vertex], indices: &[u32]) -> (Vec<Vertex>, Vec<u32>) {
    let mut out = Vec::with_capacity(indices.len());
    for tri in indices.chunks_exact(3) {
        let v = [vertices[tri[0] as usize], vertices[tri[1] as usize], vertices[tri[2] as usize]];
        let n = face_normal_unnormalised(v[0].position, v[1].position, v[2].position)
            .try_normalize()
            .unwrap_or(Vec3::Y);
        for mut vertex in v {
            vertex.normal = n.to_array();
            out.push(vertex);
        }
    }
    let indices = (0..out.len() as u32).collect();
    (out, indices)
}

/// Area-weighted smooth normals per position (the unnormalised cross product
/// is twice the triangle area). `triangles` index into `positions`.
pub fn smooth_normals(positions: &[Vec3], triangles: &[[usize; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for &[a, b, c] in triangles {
        let n = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        if n.is_finite() {
            normals[a] += n;
            normals[b] += n;
            normals[c] += n;
        }
    }
    normals.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Y)).collect()
}

fn face_normal_unnormalised(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Vec3 {
    let a = Vec3::from(a);
    (Vec3::from(b) - a).cross(Vec3::from(c) - a)
}

/// Object-space bounds of a vertex list.
pub fn bounds_of(vertices: &[Vertex]) -> Aabb {
    let mut b = Aabb::EMPTY;
    for v in vertices {
        b.grow(Vec3::from(v.position));
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit quad in the XY plane facing +Z, two CCW triangles.
    fn quad(uvs: [[f32; 2]; 4]) -> (Vec<Vertex>, Vec<u32>) {
        let pos = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let vertices = pos
            .iter()
            .zip(uvs)
            .map(|(&position, uv)| Vertex { position, normal: [0.0, 0.0, 1.0], uv, tangent: [0.0; 4] })
            .collect();
        (vertices, vec![0, 1, 2, 0, 2, 3])
    }

    fn assert_tangent(v: &Vertex, expected: [f32; 4]) {
        let d = Vec4::from(v.tangent) - Vec4::from(expected);
        assert!(d.abs().max_element() < 1e-5, "tangent {:?}, expected {:?}", v.tangent, expected);
    }

    #[test]
    fn quad_tangent_follows_u_with_positive_handedness() {
        let (mut v, i) = quad([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        generate_tangents(&mut v, &i);
        // +u runs along +X; +v along +Y = cross(+Z, +X), so w = +1.
        for vertex in &v {
            assert_tangent(vertex, [1.0, 0.0, 0.0, 1.0]);
        }
    }

    #[test]
    fn mirrored_u_flips_tangent_and_handedness() {
        let (mut v, i) = quad([[1.0, 0.0], [0.0, 0.0], [0.0, 1.0], [1.0, 1.0]]);
        generate_tangents(&mut v, &i);
        // +u now runs along -X while +v still runs along +Y = -cross(N, T).
        for vertex in &v {
            assert_tangent(vertex, [-1.0, 0.0, 0.0, -1.0]);
        }
    }

    #[test]
    fn flipped_v_gives_negative_handedness() {
        let (mut v, i) = quad([[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]);
        generate_tangents(&mut v, &i);
        for vertex in &v {
            assert_tangent(vertex, [1.0, 0.0, 0.0, -1.0]);
        }
    }

    #[test]
    fn degenerate_uvs_get_orthogonal_fallback() {
        let (mut v, i) = quad([[0.5, 0.5]; 4]);
        generate_tangents(&mut v, &i);
        for vertex in &v {
            let t = Vec4::from(vertex.tangent);
            assert!((t.truncate().length() - 1.0).abs() < 1e-5);
            assert!(t.truncate().dot(Vec3::Z).abs() < 1e-5);
            assert_eq!(t.w, 1.0);
        }
    }

    #[test]
    fn tangent_is_orthogonalised_against_a_tilted_normal() {
        let (mut v, i) = quad([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let n = Vec3::new(0.3, 0.0, 1.0).normalize();
        for vertex in &mut v {
            vertex.normal = n.to_array();
        }
        generate_tangents(&mut v, &i);
        for vertex in &v {
            let t = Vec3::from_slice(&vertex.tangent[..3]);
            assert!(t.dot(n).abs() < 1e-5);
            assert!((t.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn flat_and_smooth_normals() {
        let (v, i) = quad([[0.0; 2]; 4]);
        let (flat, fi) = flatten_with_face_normals(&v, &i);
        assert_eq!(flat.len(), 6);
        assert_eq!(fi, vec![0, 1, 2, 3, 4, 5]);
        assert!(flat.iter().all(|v| v.normal == [0.0, 0.0, 1.0]));
        let pos: Vec<Vec3> = v.iter().map(|v| Vec3::from(v.position)).collect();
        let n = smooth_normals(&pos, &[[0, 1, 2], [0, 2, 3]]);
        assert!(n.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    }
}
