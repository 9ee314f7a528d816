//! The CPU tracer: a reference for glsl/trace/compute.glsl's tests and traversal, also used by PRT.
//! Watertight triangle test (triangle.rs), NaN-safe slab test, ordered closest-hit traversal of one
//! [`Bvh`] and of a two-level structure.
//!
//! Conventions shared with the shader:
//! * hits are reported for both windings (no culling), for `0 < t < tmax`;
//! * barycentrics `(u, v)` weigh vertices 1 and 2:
//!   `p = p0 * (1 - u - v) + p1 * u + p2 * v`;
//! * directions need not be normalised; `t` is in units of `dir`, so an
//!   object-space ray `(M * o, M * d)` yields the world-space `t`.

use glam::{Mat4, Vec3};

use super::bvh::{Bvh, BvhNode, MAX_DEPTH};
use crate::scene::{Aabb, Vertex};

mod triangle;
pub use triangle::{intersect_triangle, WatertightRay};

/// Relative widening of a box's exit distance, `1 + 2 * gamma(3)` with
/// `gamma(n) = n * eps / (1 - n * eps)` (Ize, "Robust BVH Ray Traversal",
/// JCGT 2013): covers the rounding of `(bound - o) * inv_dir` and of
/// `inv_dir` itself, so a box is never missed by a ray that hits a triangle
/// lying on its faces, edges or corners.
pub const BOX_EXIT_SCALE: f32 = 1.0 + 2.0 * (3.0 * 0.5 * f32::EPSILON) / (1.0 - 3.0 * 0.5 * f32::EPSILON);

/// Slab test: entry distance (>= `tmin`) when the ray meets `aabb` within `[tmin, tmax]`, boxes closed.
///
/// `inv_dir` may hold `+-inf`; then `(bound - o) * inv` is `+-inf` as it should be, except
/// `0 * inf = NaN` exactly when the origin lies on that face's plane and the ray runs inside it. The
/// closed slab then contains the whole ray, so a NaN axis is skipped rather than fed to min/max.
/// Inverted (empty) boxes never hit; the exit is widened by [`BOX_EXIT_SCALE`].
pub fn ray_aabb(origin: Vec3, inv_dir: Vec3, tmin: f32, tmax: f32, aabb: &Aabb) -> Option<f32> {
    let (mut enter, mut exit) = (tmin, tmax);
    for k in 0..3 {
        let (lo, hi) = (aabb.min[k], aabb.max[k]);
        if lo > hi || lo.is_nan() || hi.is_nan() {
            return None;
        }
        let t0 = (aabb.min[k] - origin[k]) * inv_dir[k];
        let t1 = (aabb.max[k] - origin[k]) * inv_dir[k];
        if t0.is_nan() || t1.is_nan() {
            continue;
        }
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        // Widen away from the entry; -inf stays -inf (no inf - inf NaN).
        let far = if far > 0.0 { far * BOX_EXIT_SCALE } else { far * (2.0 - BOX_EXIT_SCALE) };
        enter = enter.max(near);
        exit = exit.min(far);
    }
    (enter <= exit).then_some(enter)
}

fn node_aabb(n: &BvhNode) -> Aabb {
    Aabb { min: n.min.into(), max: n.max.into() }
}

/// Ordered (near child first) stack traversal. `leaf(prim, tmax)` is called
/// for every primitive of every leaf the ray reaches and may shrink `tmax`;
/// subtrees whose entry lies beyond it are skipped.
fn traverse(bvh: &Bvh, origin: Vec3, inv_dir: Vec3, tmax: &mut f32, mut leaf: impl FnMut(u32, &mut f32)) {
    let Some(root) = bvh.nodes.first() else { return };
    if ray_aabb(origin, inv_dir, 0.0, *tmax, &node_aabb(root)).is_none() {
        return;
    }
    // (node, entry distance); a tree of MAX_DEPTH levels needs MAX_DEPTH - 1.
    let mut stack: Vec<(usize, f32)> = Vec::with_capacity(MAX_DEPTH);
    let mut node = 0usize;
    loop {
        let n = &bvh.nodes[node];
        let first = n.left_or_first as usize;
        if n.count > 0 {
            for &p in &bvh.prim_indices[first..first + n.count as usize] {
                leaf(p, tmax);
            }
        } else {
            let tl = ray_aabb(origin, inv_dir, 0.0, *tmax, &node_aabb(&bvh.nodes[first]));
            let tr = ray_aabb(origin, inv_dir, 0.0, *tmax, &node_aabb(&bvh.nodes[first + 1]));
            match (tl, tr) {
                (Some(l), Some(r)) => {
                    let (near, far, t_far) =
                        if l <= r { (first, first + 1, r) } else { (first + 1, first, l) };
                    stack.push((far, t_far));
                    node = near;
                    continue;
                }
                (Some(_), None) => {
                    node = first;
                    continue;
                }
                (None, Some(_)) => {
                    node = first + 1;
                    continue;
                }
                (None, None) => {}
            }
        }
        loop {
            match stack.pop() {
                None => return,
                Some((next, t)) if t <= *tmax => {
                    node = next;
                    break;
                }
                Some(_) => {}
            }
        }
    }
}

/// Closest hit of a ray with the triangles `tris` (indexed like the
/// primitives `bvh` was built over): `(prim, t, u, v)` for `0 < t < tmax`.
pub fn traverse_closest(
    bvh: &Bvh,
    tris: &[[Vec3; 3]],
    origin: Vec3,
    dir: Vec3,
    tmax: f32,
) -> Option<(u32, f32, f32, f32)> {
    let ray = WatertightRay::new(origin, dir);
    let mut best = None;
    let mut tmax = tmax;
    traverse(bvh, origin, dir.recip(), &mut tmax, |p, tmax| {
        let t = &tris[p as usize];
        if let Some((th, u, v)) = ray.intersect(t[0], t[1], t[2], *tmax) {
            *tmax = th;
            best = Some((p, th, u, v));
        }
    });
    best
}

/// Whether any of `tris` is hit for `0 < t < tmax`: a visibility ray that
/// stops at its first hit (the PRT precompute's shadow rays).
pub fn traverse_any(bvh: &Bvh, tris: &[[Vec3; 3]], origin: Vec3, dir: Vec3, tmax: f32) -> bool {
    let ray = WatertightRay::new(origin, dir);
    let mut hit = false;
    let mut tmax = tmax;
    traverse(bvh, origin, dir.recip(), &mut tmax, |p, tmax| {
        let t = &tris[p as usize];
        if !hit && ray.intersect(t[0], t[1], t[2], *tmax).is_some() {
            hit = true;
            // Prunes every box the ray enters after its origin.
            *tmax = 0.0;
        }
    });
    hit
}

/// One placed BLAS of a two-level structure.
#[derive(Clone, Copy, Debug)]
pub struct BlasInstance<'a> {
    pub bvh: &'a Bvh,
    pub tris: &'a [[Vec3; 3]],
    pub world_to_object: Mat4,
}

/// Closest hit in a two-level structure (`tlas` leaves index `instances`); each BLAS is traversed with
/// the ray in object space, direction not renormalised so `t` stays world-space.
/// Returns `(instance, prim, t, u, v)`.
pub fn traverse_two_level(
    tlas: &Bvh,
    instances: &[BlasInstance],
    origin: Vec3,
    dir: Vec3,
    tmax: f32,
) -> Option<(u32, u32, f32, f32, f32)> {
    let mut best = None;
    let mut tmax = tmax;
    traverse(tlas, origin, dir.recip(), &mut tmax, |i, tmax| {
        let inst = &instances[i as usize];
        let o = inst.world_to_object.transform_point3(origin);
        let d = inst.world_to_object.transform_vector3(dir);
        let ray = WatertightRay::new(o, d);
        traverse(inst.bvh, o, d.recip(), tmax, |p, tmax| {
            let t = &inst.tris[p as usize];
            if let Some((th, u, v)) = ray.intersect(t[0], t[1], t[2], *tmax) {
                *tmax = th;
                best = Some((i, p, th, u, v));
            }
        });
    });
    best
}

/// Vertex positions of every triangle of an indexed mesh.
pub fn triangle_positions(vertices: &[Vertex], indices: &[u32]) -> Vec<[Vec3; 3]> {
    let p = |i: u32| Vec3::from(vertices[i as usize].position);
    indices.chunks_exact(3).map(|t| [p(t[0]), p(t[1]), p(t[2])]).collect()
}

#[cfg(test)]
mod tests;
