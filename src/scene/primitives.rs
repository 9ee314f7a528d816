//! Procedural meshes for scene files and tests. Right-handed, +Y up,
//! counter-clockwise front faces and UV origin at the top-left of the image
//! (glTF conventions), so they shade exactly like imported content.

use std::f32::consts::PI;

use glam::Vec3;

use super::tangents::{bounds_of, generate_tangents};
use super::{Primitive, Vertex};

/// A `size_x` × `size_z` rectangle in the XZ plane, centred at the origin,
/// facing +Y. The texture's top edge lies at -Z.
pub fn plane(size_x: f32, size_z: f32) -> Primitive {
    let mut vertices = Vec::with_capacity(4);
    let mut indices = Vec::with_capacity(6);
    let half = Vec3::new(size_x.abs() * 0.5, 0.0, size_z.abs() * 0.5);
    push_face(&mut vertices, &mut indices, Face { n: Vec3::Y, right: Vec3::X, up: Vec3::NEG_Z }, half);
    finish(vertices, indices)
}

/// An axis-aligned cube of edge `size` centred at the origin: 24 vertices so
/// every face has its own normal and a full 0..1 UV square.
pub fn cube(size: f32) -> Primitive {
    let h = size.abs() * 0.5;
    let mut vertices = Vec::with_capacity(24);
    let mut indices = Vec::with_capacity(36);
    // (normal, right, up) as seen from outside: right × up = normal.
    let faces = [
        Face { n: Vec3::X, right: Vec3::NEG_Z, up: Vec3::Y },
        Face { n: Vec3::NEG_X, right: Vec3::Z, up: Vec3::Y },
        Face { n: Vec3::Y, right: Vec3::X, up: Vec3::NEG_Z },
        Face { n: Vec3::NEG_Y, right: Vec3::X, up: Vec3::Z },
        Face { n: Vec3::Z, right: Vec3::X, up: Vec3::Y },
        Face { n: Vec3::NEG_Z, right: Vec3::NEG_X, up: Vec3::Y },
    ];
    for face in faces {
        push_face(&mut vertices, &mut indices, face, Vec3::splat(h));
    }
    finish(vertices, indices)
}

/// A latitude/longitude sphere. `slices` (around Y) is raised to at least 3
/// and `stacks` (pole to pole) to at least 2 so the result is always a
/// closed solid. u runs eastwards around +Y, v from the north pole (v = 0)
/// to the south pole; the seam column is duplicated so UVs do not wrap.
pub fn uv_sphere(radius: f32, slices: u32, stacks: u32) -> Primitive {
    let slices = slices.max(3);
    let stacks = stacks.max(2);
    let radius = radius.abs();
    let mut vertices = Vec::with_capacity(((slices + 1) * (stacks + 1)) as usize);
    for i in 0..=stacks {
        let v = i as f32 / stacks as f32;
        let theta = v * PI;
        for j in 0..=slices {
            let u = j as f32 / slices as f32;
            vertices.push(sphere_vertex(radius, u, v, theta, u * 2.0 * PI));
        }
    }
    let row = slices + 1;
    let mut indices = Vec::with_capacity((slices * stacks * 6) as usize);
    for i in 0..stacks {
        for j in 0..slices {
            // Quad corners as seen from outside: a top-left, b bottom-left,
            // c bottom-right, d top-right.
            let a = i * row + j;
            let (b, c, d) = (a + row, a + row + 1, a + 1);
            // The triangle touching a pole with two corners would be degenerate.
            if i != stacks - 1 {
                indices.extend_from_slice(&[a, b, c]);
            }
            if i != 0 {
                indices.extend_from_slice(&[a, c, d]);
            }
        }
    }
    let bounds = bounds_of(&vertices);
    Primitive { vertices, indices, material: 0, bounds, skin: None }
}

/// Most cells per side of a [`terrain`]: bounds its vertex allocation (4097² vertices, 1.5 GiB at 48
/// bytes) for any input.
pub const TERRAIN_MAX_CELLS: u32 = 4096;

/// A `size_x` × `size_z` height field centred at the origin in the XZ plane, facing +Y:
/// `cells_x` × `cells_z` quads (two triangles each, so `2 cx cz` unique triangles), heights within
/// ±`height` from a fixed sum of sine octaves (rolling hills with finer ridges: every cell differs, so
/// the geometry is as unique as a scanned terrain's and the same for every run). UVs span the whole
/// field once, like [`plane`]'s. For scale tests: the triangle count is what the caller asks for.
pub fn terrain(size_x: f32, size_z: f32, cells_x: u32, cells_z: u32, height: f32) -> Primitive {
    let (cx, cz) = (cells_x.clamp(1, TERRAIN_MAX_CELLS), cells_z.clamp(1, TERRAIN_MAX_CELLS));
    let (sx, sz) = (size_x.abs(), size_z.abs());
    let row = cx + 1;
    let mut vertices = Vec::with_capacity((row * (cz + 1)) as usize);
    for j in 0..=cz {
        let v = j as f32 / cz as f32;
        for i in 0..=cx {
            let u = i as f32 / cx as f32;
            let (x, z) = ((u - 0.5) * sx, (v - 0.5) * sz);
            let (h, dhdx, dhdz) = terrain_height(x / sx.max(sz), z / sx.max(sz));
            let scale = height / sx.max(sz);
            let (dhdx, dhdz) = (dhdx * scale, dhdz * scale);
            let n = Vec3::new(-dhdx, 1.0, -dhdz).normalize();
            // dP/du runs along +X (with the slope); dP/dv along +Z (the texture's top edge is at -Z).
            let dpdu = Vec3::new(1.0, dhdx, 0.0);
            let tangent = (dpdu - n * n.dot(dpdu)).normalize();
            let dpdv = Vec3::new(0.0, dhdz, 1.0);
            let w = if n.cross(tangent).dot(dpdv) < 0.0 { -1.0 } else { 1.0 };
            vertices.push(Vertex {
                position: [x, h * height, z],
                normal: n.to_array(),
                uv: [u, v],
                tangent: tangent.extend(w).to_array(),
            });
        }
    }
    let mut indices = Vec::with_capacity((cx * cz * 6) as usize);
    for j in 0..cz {
        for i in 0..cx {
            // a top-left, b bottom-left, c bottom-right, d top-right as seen from above (+Z is down).
            let a = j * row + i;
            let (b, c, d) = (a + row, a + row + 1, a + 1);
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    let bounds = bounds_of(&vertices);
    Primitive { vertices, indices, material: 0, bounds, skin: None }
}

/// Height in [-1, 1] at `(x, z)` in units of the terrain's larger side, with its derivatives there:
/// six octaves of products of sines at irrational-ish frequency ratios and fixed phases.
fn terrain_height(x: f32, z: f32) -> (f32, f32, f32) {
    const OCTAVES: [(f32, f32, f32, f32); 6] = [
        (3.1, 2.3, 0.4, 1.3),
        (7.3, 5.9, 2.1, 0.2),
        (13.7, 17.1, 4.0, 2.9),
        (31.3, 27.7, 1.7, 5.1),
        (61.9, 71.3, 3.3, 0.7),
        (137.1, 119.3, 0.9, 4.4),
    ];
    let (mut h, mut dx, mut dz, mut amplitude, mut total) = (0.0, 0.0, 0.0, 1.0, 0.0);
    for (fx, fz, px, pz) in OCTAVES {
        let (sx, cx) = (fx * x + px).sin_cos();
        let (sz, cz) = (fz * z + pz).sin_cos();
        h += amplitude * sx * sz;
        dx += amplitude * fx * cx * sz;
        dz += amplitude * fz * sx * cz;
        total += amplitude;
        amplitude *= 0.55;
    }
    (h / total, dx / total, dz / total)
}

/// One sphere vertex with its analytic tangent (along +u), which stays
/// defined at the poles where the UV derivatives degenerate.
fn sphere_vertex(radius: f32, u: f32, v: f32, theta: f32, phi: f32) -> Vertex {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    let n = Vec3::new(st * cp, ct, -st * sp);
    let tangent = Vec3::new(-sp, 0.0, -cp);
    // dP/dv points south (towards +theta); w makes cross(N, T) * w match it.
    let dpdv = Vec3::new(ct * cp, -st, -ct * sp);
    let w = if n.cross(tangent).dot(dpdv) < 0.0 { -1.0 } else { 1.0 };
    Vertex {
        position: (n * radius).to_array(),
        normal: n.to_array(),
        uv: [u, v],
        tangent: tangent.extend(w).to_array(),
    }
}

/// Orientation of one flat quad: outward normal and the in-plane axes that
/// point to the texture's right and top edge.
struct Face {
    n: Vec3,
    right: Vec3,
    up: Vec3,
}

/// Appends a quad at `n * half.dot(|n|)` spanning `half` along its axes.
fn push_face(vertices: &mut Vec<Vertex>, indices: &mut Vec<u32>, f: Face, half: Vec3) {
    let extent = |axis: Vec3| axis.abs().dot(half);
    let (center, hr, hu) = (f.n * extent(f.n), extent(f.right), extent(f.up));
    let base = vertices.len() as u32;
    // Top-left, top-right, bottom-right, bottom-left with v growing downwards.
    for uv in [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
        let p = center + f.right * (2.0 * uv[0] - 1.0) * hr + f.up * (1.0 - 2.0 * uv[1]) * hu;
        vertices.push(Vertex { position: p.to_array(), normal: f.n.to_array(), uv, tangent: [0.0; 4] });
    }
    // TL -> BL -> BR and TL -> BR -> TR are counter-clockwise from outside.
    indices.extend([0, 3, 2, 0, 2, 1].map(|i| base + i));
}

fn finish(mut vertices: Vec<Vertex>, indices: Vec<u32>) -> Primitive {
    generate_tangents(&mut vertices, &indices);
    let bounds = bounds_of(&vertices);
    Primitive { vertices, indices, material: 0, bounds, skin: None }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit normals and tangents, tangent ⟂ normal, |w| = 1, and every
    /// triangle's geometric (CCW) normal agrees with its vertex normals.
    fn check(p: &Primitive) {
        assert!(!p.indices.is_empty());
        assert_eq!(p.indices.len() % 3, 0);
        for v in &p.vertices {
            let n = Vec3::from(v.normal);
            let t = Vec3::from_slice(&v.tangent[..3]);
            assert!((n.length() - 1.0).abs() < 1e-4, "normal {n}");
            assert!((t.length() - 1.0).abs() < 1e-4, "tangent {t}");
            assert!(n.dot(t).abs() < 1e-4, "tangent {t} not orthogonal to {n}");
            assert!(v.tangent[3].abs() == 1.0);
            assert!(p.bounds.min.cmple(Vec3::from(v.position)).all());
            assert!(p.bounds.max.cmpge(Vec3::from(v.position)).all());
        }
        for tri in p.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| p.vertices[tri[k] as usize]);
            let pa = Vec3::from(a.position);
            let g = (Vec3::from(b.position) - pa).cross(Vec3::from(c.position) - pa);
            assert!(g.length() > 1e-9, "degenerate triangle {tri:?}");
            for v in [a, b, c] {
                assert!(g.normalize().dot(Vec3::from(v.normal)) > 0.0, "triangle {tri:?} is clockwise");
            }
        }
    }

    #[test]
    fn plane_faces_up() {
        let p = plane(4.0, 2.0);
        check(&p);
        assert_eq!(p.vertices.len(), 4);
        assert_eq!(p.bounds.min, Vec3::new(-2.0, 0.0, -1.0));
        assert_eq!(p.bounds.max, Vec3::new(2.0, 0.0, 1.0));
        assert!(p.vertices.iter().all(|v| v.normal == [0.0, 1.0, 0.0]));
    }

    #[test]
    fn cube_has_24_vertices_and_outward_faces() {
        let p = cube(2.0);
        check(&p);
        assert_eq!(p.vertices.len(), 24);
        assert_eq!(p.indices.len(), 36);
        assert_eq!(p.bounds.min, Vec3::splat(-1.0));
        for v in &p.vertices {
            // The face normal points the way its face is displaced.
            assert!(Vec3::from(v.position).dot(Vec3::from(v.normal)) > 0.99);
        }
    }

    #[test]
    fn sphere_is_closed_and_outward() {
        let p = uv_sphere(0.5, 16, 8);
        check(&p);
        for v in &p.vertices {
            assert!((Vec3::from(v.position).length() - 0.5).abs() < 1e-5);
        }
        // 2 triangles per quad, minus one per slice at each pole.
        assert_eq!(p.indices.len() / 3, 16 * 8 * 2 - 2 * 16);
    }

    #[test]
    fn sphere_parameters_are_clamped() {
        let p = uv_sphere(1.0, 0, 0);
        check(&p);
        assert_eq!(p.indices.len() / 3, 3 * 2 * 2 - 2 * 3);
    }

    #[test]
    fn terrain_has_two_triangles_per_cell_within_its_height() {
        let p = terrain(40.0, 20.0, 64, 32, 3.0);
        check(&p);
        assert_eq!(p.indices.len() / 3, 2 * 64 * 32);
        assert_eq!(p.vertices.len(), 65 * 33);
        assert_eq!(
            (p.bounds.min.x, p.bounds.max.x, p.bounds.min.z, p.bounds.max.z),
            (-20.0, 20.0, -10.0, 10.0)
        );
        assert!(p.bounds.min.y >= -3.0 && p.bounds.max.y <= 3.0);
        // Hills, not a plane: the heights use a good part of the range.
        assert!(p.bounds.max.y - p.bounds.min.y > 2.0, "{:?}", p.bounds);
        // Deterministic, and unique geometry: no two cells alike.
        assert_eq!(p.vertices, terrain(40.0, 20.0, 64, 32, 3.0).vertices);
        let mut heights: Vec<u32> = p.vertices.iter().map(|v| v.position[1].to_bits()).collect();
        heights.sort_unstable();
        heights.dedup();
        assert!(heights.len() > p.vertices.len() * 9 / 10, "{} distinct heights", heights.len());
        assert_eq!(terrain(1.0, 1.0, 0, 1 << 20, 1.0).indices.len() / 3, 2 * TERRAIN_MAX_CELLS as usize);
    }

    #[test]
    fn terrain_normals_and_tangents_match_the_surface() {
        let analytic = terrain(10.0, 10.0, 256, 256, 1.0);
        let mut generated = analytic.clone();
        generate_tangents(&mut generated.vertices, &generated.indices);
        let row = 257;
        for (k, (a, g)) in analytic.vertices.iter().zip(&generated.vertices).enumerate() {
            let d = Vec3::from_slice(&a.tangent[..3]).dot(Vec3::from_slice(&g.tangent[..3]));
            assert!(d > 0.99, "vertex {k}: {a:?} vs {g:?}");
            assert_eq!(a.tangent[3], g.tangent[3], "vertex {k}");
            // Inner vertices: the analytic normal agrees with the mesh's (central differences).
            let (i, j) = (k % row, k / row);
            if (1..row - 1).contains(&i) && (1..row - 1).contains(&j) {
                let p = |k: usize| Vec3::from(analytic.vertices[k].position);
                let n = (p(k + row) - p(k - row)).cross(p(k + 1) - p(k - 1)).normalize();
                assert!(n.dot(Vec3::from(a.normal)) > 0.999, "vertex {k}: {n} vs {:?}", a.normal);
            }
        }
    }

    #[test]
    fn sphere_tangents_match_generated_ones_away_from_poles() {
        let analytic = uv_sphere(1.0, 32, 16);
        let mut generated = analytic.clone();
        generate_tangents(&mut generated.vertices, &generated.indices);
        for (a, g) in analytic.vertices.iter().zip(&generated.vertices) {
            if a.normal[1].abs() < 0.9 {
                let d = Vec3::from_slice(&a.tangent[..3]).dot(Vec3::from_slice(&g.tangent[..3]));
                assert!(d > 0.99, "{a:?} vs {g:?}");
                assert_eq!(a.tangent[3], g.tangent[3]);
            }
        }
    }
}
