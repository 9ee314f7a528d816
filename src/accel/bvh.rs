//! Binned-SAH BVH over axis-aligned boxes, flat 32-byte nodes for the GPU.
//!
//! Layout (read by glsl/trace/compute.glsl): `count == 0` marks an interior
//! node whose children are `left_or_first` and `left_or_first + 1`; a leaf
//! covers `prim_indices[left_or_first .. left_or_first + count]`. Children
//! always come after their parent, so a reverse sweep refits bottom-up.

use glam::Vec3;

use crate::scene::{Aabb, Vertex};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub count: u32,
}
const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);

/// SAH constants: cost of one node visit and of one primitive test.
const TRAVERSAL_COST: f32 = 1.0;
const INTERSECTION_COST: f32 = 1.0;
const BINS: usize = 16;
const MAX_LEAF: usize = 4;

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub prim_indices: Vec<u32>,
}

fn area(b: &Aabb) -> f32 {
    if b.is_empty() {
        return 0.0;
    }
    let e = b.max - b.min;
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

fn node_aabb(n: &BvhNode) -> Aabb {
    Aabb { min: n.min.into(), max: n.max.into() }
}

impl Bvh {
    /// Builds over `aabbs` (one per primitive). Empty input gives an empty
    /// BVH (no nodes); callers skip such primitives.
    pub fn build(aabbs: &[Aabb]) -> Bvh {
        if aabbs.is_empty() {
            return Bvh::default();
        }
        let centroids: Vec<Vec3> = aabbs.iter().map(|b| b.center()).collect();
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * aabbs.len()),
            prim_indices: (0..aabbs.len() as u32).collect(),
        };
        bvh.nodes.push(BvhNode::default());
        // Explicit work list: (node index, first, count).
        let mut work = vec![(0usize, 0usize, aabbs.len())];
        while let Some((node, first, count)) = work.pop() {
            let mut bounds = Aabb::EMPTY;
            let mut cbounds = Aabb::EMPTY;
            for &p in &bvh.prim_indices[first..first + count] {
                bounds = bounds.union(&aabbs[p as usize]);
                cbounds.grow(centroids[p as usize]);
            }
            bvh.nodes[node].min = bounds.min.into();
            bvh.nodes[node].max = bounds.max.into();
            let split = if count > 1 {
                find_split(&bvh.prim_indices[first..first + count], aabbs, &centroids, &cbounds, &bounds)
            } else {
                None
            };
            let mid = match split {
                Some((axis, pos)) => {
                    let slice = &mut bvh.prim_indices[first..first + count];
                    let m = partition(slice, |p| centroids[p as usize][axis] < pos);
                    if m == 0 || m == count {
                        None
                    } else {
                        Some(m)
                    }
                }
                // All centroids coincide but the node is too big for a leaf:
                // split the list in the middle.
                None if count > MAX_LEAF => Some(count / 2),
                None => None,
            };
            match mid {
                Some(m) => {
                    let left = bvh.nodes.len();
                    bvh.nodes.push(BvhNode::default());
                    bvh.nodes.push(BvhNode::default());
                    bvh.nodes[node].left_or_first = left as u32;
                    bvh.nodes[node].count = 0;
                    work.push((left + 1, first + m, count - m));
                    work.push((left, first, m));
                }
                None => {
                    bvh.nodes[node].left_or_first = first as u32;
                    bvh.nodes[node].count = count as u32;
                }
            }
        }
        bvh
    }

    /// Recomputes every node's bounds for moved primitives (same topology).
    pub fn refit(&mut self, aabbs: &[Aabb]) {
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            let b = if n.count > 0 {
                let s = n.left_or_first as usize;
                self.prim_indices[s..s + n.count as usize]
                    .iter()
                    .fold(Aabb::EMPTY, |acc, &p| acc.union(&aabbs[p as usize]))
            } else {
                let l = n.left_or_first as usize;
                node_aabb(&self.nodes[l]).union(&node_aabb(&self.nodes[l + 1]))
            };
            self.nodes[i].min = b.min.into();
            self.nodes[i].max = b.max.into();
        }
    }

    /// SAH cost normalised by the root's surface area.
    pub fn sah_cost(&self) -> f32 {
        let Some(root) = self.nodes.first() else { return 0.0 };
        let ra = area(&node_aabb(root)).max(f32::MIN_POSITIVE);
        self.nodes
            .iter()
            .map(|n| {
                let a = area(&node_aabb(n)) / ra;
                if n.count > 0 {
                    a * INTERSECTION_COST * n.count as f32
                } else {
                    a * TRAVERSAL_COST
                }
            })
            .sum()
    }

    pub fn depth(&self) -> usize {
        if self.nodes.is_empty() {
            return 0;
        }
        let mut max = 0;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            max = max.max(d);
            let n = self.nodes[i];
            if n.count == 0 {
                stack.push((n.left_or_first as usize, d + 1));
                stack.push((n.left_or_first as usize + 1, d + 1));
            }
        }
        max
    }

    /// Checks the invariants: indices in range, children after parents,
    /// every primitive in exactly one leaf, bounds containing their content.
    pub fn validate(&self, aabbs: &[Aabb]) -> Result<(), String> {
        let contains = |outer: &Aabb, inner: &Aabb| {
            inner.is_empty() || (outer.min.cmple(inner.min).all() && outer.max.cmpge(inner.max).all())
        };
        let mut seen = vec![0u32; aabbs.len()];
        for (i, n) in self.nodes.iter().enumerate() {
            let b = node_aabb(n);
            if n.count == 0 {
                let l = n.left_or_first as usize;
                if l <= i || l + 1 >= self.nodes.len() {
                    return Err(format!("node {i}: children {l} out of order or range"));
                }
                for c in [l, l + 1] {
                    if !contains(&b, &node_aabb(&self.nodes[c])) {
                        return Err(format!("node {i} does not contain child {c}"));
                    }
                }
            } else {
                let s = n.left_or_first as usize;
                let e = s + n.count as usize;
                if e > self.prim_indices.len() {
                    return Err(format!("leaf {i}: primitives {s}..{e} out of range"));
                }
                for &p in &self.prim_indices[s..e] {
                    let p = p as usize;
                    if p >= aabbs.len() {
                        return Err(format!("leaf {i}: primitive {p} out of range"));
                    }
                    seen[p] += 1;
                    if !contains(&b, &aabbs[p]) {
                        return Err(format!("leaf {i} does not contain primitive {p}"));
                    }
                }
            }
        }
        match seen.iter().position(|&c| c != 1) {
            Some(p) => Err(format!("primitive {p} referenced {} times", seen[p])),
            None => Ok(()),
        }
    }
}

/// In-place partition; returns the number of elements for which `pred` holds.
fn partition(slice: &mut [u32], pred: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    for j in 0..slice.len() {
        if pred(slice[j]) {
            slice.swap(i, j);
            i += 1;
        }
    }
    i
}

/// Best binned-SAH split (axis, centroid position), or None when a leaf is
/// cheaper (and small enough) or all centroids coincide.
fn find_split(
    prims: &[u32],
    aabbs: &[Aabb],
    centroids: &[Vec3],
    cb: &Aabb,
    bounds: &Aabb,
) -> Option<(usize, f32)> {
    let extent = cb.max - cb.min;
    let mut best: Option<(f32, usize, f32)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 || !extent[axis].is_finite() {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_count = [0usize; BINS];
        for &p in prims {
            let b = (((centroids[p as usize][axis] - cb.min[axis]) * scale) as usize).min(BINS - 1);
            bin_count[b] += 1;
            bin_bounds[b] = bin_bounds[b].union(&aabbs[p as usize]);
        }
        // Sweep from the right to get suffix areas, then from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for i in (1..BINS).rev() {
            acc = acc.union(&bin_bounds[i]);
            n += bin_count[i];
            right_area[i] = area(&acc);
            right_count[i] = n;
        }
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for i in 0..BINS - 1 {
            acc = acc.union(&bin_bounds[i]);
            n += bin_count[i];
            if n == 0 || right_count[i + 1] == 0 {
                continue;
            }
            let cost = area(&acc) * n as f32 + right_area[i + 1] * right_count[i + 1] as f32;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, cb.min[axis] + (i + 1) as f32 / scale));
            }
        }
    }
    let (cost, axis, pos) = best?;
    let parent = area(bounds).max(f32::MIN_POSITIVE);
    let split_cost = TRAVERSAL_COST + INTERSECTION_COST * cost / parent;
    let leaf_cost = INTERSECTION_COST * prims.len() as f32;
    if prims.len() <= MAX_LEAF && leaf_cost <= split_cost {
        return None;
    }
    Some((axis, pos))
}

/// One object-space box per triangle.
pub fn triangle_aabbs(vertices: &[Vertex], indices: &[u32]) -> Vec<Aabb> {
    indices
        .chunks_exact(3)
        .map(|t| {
            let mut b = Aabb::EMPTY;
            for &i in t {
                b.grow(Vec3::from(vertices[i as usize].position));
            }
            b
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::primitives::uv_sphere;

    fn lcg(seed: &mut u64) -> f32 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 40) as f32) / (1u64 << 24) as f32
    }

    fn soup(n: usize, seed: u64) -> Vec<Aabb> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                let c = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 100.0;
                let e = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s));
                Aabb { min: c - e, max: c + e }
            })
            .collect()
    }

    #[test]
    fn random_soups_are_valid() {
        for (n, seed) in [(1, 1), (2, 2), (3, 3), (17, 4), (1000, 5), (20000, 6)] {
            let a = soup(n, seed);
            let bvh = Bvh::build(&a);
            bvh.validate(&a).unwrap();
            assert!(bvh.sah_cost() > 0.0);
        }
        assert!(Bvh::build(&[]).nodes.is_empty());
    }

    #[test]
    fn identical_and_degenerate_boxes_still_build() {
        let b = Aabb { min: Vec3::ONE, max: Vec3::ONE };
        let a = vec![b; 1000];
        let bvh = Bvh::build(&a);
        bvh.validate(&a).unwrap();
        assert!(bvh.nodes.iter().all(|n| n.count as usize <= MAX_LEAF));
    }

    #[test]
    fn sphere_bvh_is_valid_and_refits() {
        let p = uv_sphere(1.0, 64, 32);
        let a = triangle_aabbs(&p.vertices, &p.indices);
        let mut bvh = Bvh::build(&a);
        bvh.validate(&a).unwrap();
        eprintln!("sphere: {} tris, SAH {:.2}, depth {}", a.len(), bvh.sah_cost(), bvh.depth());
        let moved: Vec<Aabb> =
            a.iter().map(|b| Aabb { min: b.min * 2.0 + Vec3::X, max: b.max * 2.0 + Vec3::X }).collect();
        bvh.refit(&moved);
        bvh.validate(&moved).unwrap();
    }
}
