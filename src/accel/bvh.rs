//! Binned-SAH BVH over axis-aligned boxes, flat 32-byte nodes for the GPU.
//!
//! Layout (read by glsl/trace/compute.glsl, keep both in sync):
//!
//! ```text
//! struct BvhNode {           // 32 bytes, std430/scalar compatible
//!     float min[3];          //  0: bounds
//!     uint  left_or_first;   // 12
//!     float max[3];          // 16
//!     uint  count;           // 28
//! };
//! ```
//!
//! * `count == 0`: interior node; its children are nodes `left_or_first` and
//!   `left_or_first + 1` (siblings are always adjacent). Node indices are
//!   local to one BVH; the root is node 0.
//! * `count > 0`: leaf over `prim_indices[left_or_first .. left_or_first +
//!   count]`, which hold indices into the primitive list given to
//!   [`Bvh::build`] (triangle `i` = indices `3i, 3i+1, 3i+2` for a BLAS,
//!   an instance index for a top level). `1 <= count <= MAX_LEAF`.
//! * Children always have larger indices than their parent, so one reverse
//!   sweep over `nodes` refits bottom-up ([`Bvh::refit`]).
//! * The tree is at most [`MAX_DEPTH`] levels deep (root = level 1), so an
//!   ordered stack traversal never holds more than `MAX_DEPTH - 1` entries.
//! * An empty primitive list gives an empty BVH (no nodes at all); callers
//!   skip such primitives (the renderer builds no BLAS for them).
//!
//! Build: top-down binned SAH ([`BINS`] bins, fewer for nodes of under 8
//! primitives, on each axis with a non-zero centroid extent, all three
//! binned in one pass; the best plane over all axes wins: about 4% lower
//! SAH cost than binning only the largest axis, for twice the binning
//! work), iterative with an explicit work stack, primitives partitioned in
//! place by the same bin function that binned them (so a chosen plane never
//! leaves a side empty). Nodes of more than [`MAX_LEAF`] primitives are
//! always split; smaller ones become leaves when the SAH says a leaf is no
//! more expensive. Coincident centroids (no binning plane separates them)
//! and subtrees that would exceed [`MAX_DEPTH`] fall back to an object
//! median split along the largest centroid axis.

use glam::Vec3;

use crate::scene::{Aabb, Scene, Vertex};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub count: u32,
}
const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);
const _: () = assert!(std::mem::align_of::<BvhNode>() == 4);

/// SAH cost of visiting one interior node (box tests of its two children).
pub const TRAVERSAL_COST: f32 = 1.0;
/// SAH cost of one primitive intersection test.
pub const INTERSECTION_COST: f32 = 1.0;
/// Bins per axis of the binned SAH.
pub const BINS: usize = 16;
/// Largest number of primitives in one leaf.
pub const MAX_LEAF: usize = 4;
/// Deepest level the builder produces (root = 1). A traversal stack of
/// `MAX_DEPTH - 1` entries (the GLSL uses 32) is therefore never exceeded.
pub const MAX_DEPTH: usize = 32;

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub prim_indices: Vec<u32>,
}

/// Plain-array box used by the builder (cheap component access at the
/// crate's opt-level 1).
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: [f32; 3],
    max: [f32; 3],
}

impl Bounds {
    const EMPTY: Bounds = Bounds { min: [f32::INFINITY; 3], max: [f32::NEG_INFINITY; 3] };

    #[inline(always)]
    fn from_aabb(b: &Aabb) -> Bounds {
        Bounds { min: b.min.to_array(), max: b.max.to_array() }
    }

    #[inline(always)]
    fn of_node(n: &BvhNode) -> Bounds {
        Bounds { min: n.min, max: n.max }
    }

    #[inline(always)]
    fn grow(&mut self, b: &Bounds) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(b.min[k]);
            self.max[k] = self.max[k].max(b.max[k]);
        }
    }

    #[inline(always)]
    fn grow_point(&mut self, p: &[f32; 3]) {
        for (k, &c) in p.iter().enumerate() {
            self.min[k] = self.min[k].min(c);
            self.max[k] = self.max[k].max(c);
        }
    }

    /// Surface area; 0 for empty (inverted) boxes.
    #[inline(always)]
    fn area(&self) -> f32 {
        let (x, y, z) = (self.max[0] - self.min[0], self.max[1] - self.min[1], self.max[2] - self.min[2]);
        if x >= 0.0 && y >= 0.0 && z >= 0.0 {
            2.0 * (x * y + y * z + z * x)
        } else {
            0.0
        }
    }

    #[inline(always)]
    fn centroid(&self) -> [f32; 3] {
        [
            0.5 * (self.min[0] + self.max[0]),
            0.5 * (self.min[1] + self.max[1]),
            0.5 * (self.min[2] + self.max[2]),
        ]
    }

    fn contains(&self, inner: &Bounds) -> bool {
        let empty = (0..3).any(|k| inner.min[k] > inner.max[k]);
        empty || (0..3).all(|k| self.min[k] <= inner.min[k] && self.max[k] >= inner.max[k])
    }

    fn to_node(self, left_or_first: u32, count: u32) -> BvhNode {
        BvhNode { min: self.min, left_or_first, max: self.max, count }
    }
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Bounds,
    count: u32,
}

const EMPTY_BIN: Bin = Bin { bounds: Bounds::EMPTY, count: 0 };

/// Bin of a centroid coordinate. Used for both binning and partitioning, so
/// the two always agree (a chosen split never leaves a side empty). NaN
/// lands in bin 0 (saturating cast).
#[inline(always)]
fn bin_of(c: f32, cmin: f32, scale: f32, nbins: usize) -> usize {
    (((c - cmin) * scale) as usize).min(nbins - 1)
}

/// Bins used for a node of `count` primitives: fewer for small nodes,
/// whose fixed binning cost would otherwise dominate the build.
#[inline(always)]
fn bin_count(count: usize) -> usize {
    (2 * count).clamp(4, BINS)
}

/// Levels a balanced subtree over `count` primitives needs below its root.
fn levels_needed(count: usize) -> usize {
    let leaves = count.div_ceil(MAX_LEAF);
    (usize::BITS - leaves.saturating_sub(1).leading_zeros()) as usize // ceil(log2(leaves))
}

struct Task {
    node: usize,
    first: usize,
    count: usize,
    depth: usize,
    /// Bounds of the primitives' centroids.
    cb: Bounds,
}

enum Decision {
    Leaf,
    /// SAH plane: primitives whose bin on `axis` is <= `bin` go left.
    Sah {
        axis: usize,
        bin: usize,
        left: Bounds,
        right: Bounds,
    },
    /// Object median along the largest centroid axis.
    Median,
}

impl Bvh {
    /// Builds over `aabbs` (one per primitive). Empty input gives an empty
    /// BVH (no nodes): callers skip such primitives.
    pub fn build(aabbs: &[Aabb]) -> Bvh {
        let n = aabbs.len();
        if n == 0 {
            return Bvh::default();
        }
        assert!(n < (u32::MAX / 2) as usize, "BVH over {n} primitives: node indices overflow u32");
        let boxes: Vec<Bounds> = aabbs.iter().map(Bounds::from_aabb).collect();
        let centroids: Vec<[f32; 3]> = boxes.iter().map(Bounds::centroid).collect();
        let mut prims: Vec<u32> = (0..n as u32).collect();
        // A binary tree with at least one primitive per leaf: <= 2n - 1 nodes.
        let mut nodes: Vec<BvhNode> = Vec::with_capacity(2 * n - 1);

        let (mut root, mut root_cb) = (Bounds::EMPTY, Bounds::EMPTY);
        for (b, c) in boxes.iter().zip(&centroids) {
            root.grow(b);
            root_cb.grow_point(c);
        }
        nodes.push(root.to_node(0, 0));
        let mut stack = Vec::with_capacity(2 * MAX_DEPTH);
        stack.push(Task { node: 0, first: 0, count: n, depth: 1, cb: root_cb });

        while let Some(task) = stack.pop() {
            let range = task.first..task.first + task.count;
            let bounds = Bounds::of_node(&nodes[task.node]);
            let decision = decide(&prims[range.clone()], &boxes, &centroids, &bounds, &task);
            let slice = &mut prims[range];
            let (m, lb, rb, lcb, rcb) = match decision {
                Decision::Leaf => {
                    nodes[task.node].left_or_first = task.first as u32;
                    nodes[task.node].count = task.count as u32;
                    continue;
                }
                Decision::Sah { axis, bin, left, right } => {
                    let nbins = bin_count(task.count);
                    let (cmin, scale) = axis_scale(&task.cb, axis, nbins);
                    // Two-pointer partition by bin; gathers child centroid bounds.
                    let (mut lcb, mut rcb) = (Bounds::EMPTY, Bounds::EMPTY);
                    let (mut i, mut j) = (0, slice.len());
                    while i < j {
                        let c = &centroids[slice[i] as usize];
                        if bin_of(c[axis], cmin, scale, nbins) <= bin {
                            lcb.grow_point(c);
                            i += 1;
                        } else {
                            rcb.grow_point(c);
                            j -= 1;
                            slice.swap(i, j);
                        }
                    }
                    (i, left, right, lcb, rcb)
                }
                Decision::Median => {
                    let e = extent(&task.cb);
                    let axis = if e[0] >= e[1] && e[0] >= e[2] {
                        0
                    } else if e[1] >= e[2] {
                        1
                    } else {
                        2
                    };
                    let m = slice.len() / 2;
                    slice.select_nth_unstable_by(m, |&a, &b| {
                        centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
                    });
                    let (mut lb, mut rb, mut lcb, mut rcb) =
                        (Bounds::EMPTY, Bounds::EMPTY, Bounds::EMPTY, Bounds::EMPTY);
                    for (i, &p) in slice.iter().enumerate() {
                        let (b, cb) = if i < m { (&mut lb, &mut lcb) } else { (&mut rb, &mut rcb) };
                        b.grow(&boxes[p as usize]);
                        cb.grow_point(&centroids[p as usize]);
                    }
                    (m, lb, rb, lcb, rcb)
                }
            };
            debug_assert!(m > 0 && m < task.count);
            let left = nodes.len();
            nodes.push(lb.to_node(0, 0));
            nodes.push(rb.to_node(0, 0));
            nodes[task.node].left_or_first = left as u32;
            nodes[task.node].count = 0;
            let depth = task.depth + 1;
            // Left on top: depth-first, left subtree first.
            stack.push(Task { node: left + 1, first: task.first + m, count: task.count - m, depth, cb: rcb });
            stack.push(Task { node: left, first: task.first, count: m, depth, cb: lcb });
        }
        nodes.shrink_to_fit();
        Bvh { nodes, prim_indices: prims }
    }

    /// Bounds of the root (empty for an empty BVH).
    pub fn root_bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| Aabb { min: n.min.into(), max: n.max.into() })
    }

    /// Recomputes every node's bounds for moved primitives (same topology:
    /// `aabbs` must describe the same primitives as at build time). Children
    /// come after their parents, so one reverse sweep is bottom-up.
    pub fn refit(&mut self, aabbs: &[Aabb]) {
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            let first = n.left_or_first as usize;
            let mut b = Bounds::EMPTY;
            if n.count > 0 {
                for &p in &self.prim_indices[first..first + n.count as usize] {
                    b.grow(&Bounds::from_aabb(&aabbs[p as usize]));
                }
            } else {
                b = Bounds::of_node(&self.nodes[first]);
                b.grow(&Bounds::of_node(&self.nodes[first + 1]));
            }
            self.nodes[i].min = b.min;
            self.nodes[i].max = b.max;
        }
    }

    /// SAH cost of the tree normalised by the root's surface area:
    /// `sum(interior) TRAVERSAL_COST * A(n) / A(root) + sum(leaves)
    /// INTERSECTION_COST * count * A(n) / A(root)`. 0 for an empty BVH or a
    /// root without area.
    pub fn sah_cost(&self) -> f32 {
        let Some(root) = self.nodes.first() else { return 0.0 };
        let ra = Bounds::of_node(root).area();
        if ra <= 0.0 || !ra.is_finite() {
            return 0.0;
        }
        let sum: f64 = self
            .nodes
            .iter()
            .map(|n| {
                let a = Bounds::of_node(n).area() as f64;
                let c = if n.count > 0 { INTERSECTION_COST * n.count as f32 } else { TRAVERSAL_COST };
                a * c as f64
            })
            .sum();
        (sum / ra as f64) as f32
    }

    /// Number of levels (root only = 1, empty = 0).
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

    /// Node indices grouped by depth, deepest level first, plus the level
    /// boundaries into that list (`levels.len() == depth + 1`): the order a
    /// parallel refit must follow, one level at a time.
    pub fn levels(&self) -> (Vec<u32>, Vec<u32>) {
        let mut depth = vec![0usize; self.nodes.len()];
        // Children come after their parents, so one forward sweep suffices.
        for (i, n) in self.nodes.iter().enumerate() {
            if n.count == 0 {
                let c = n.left_or_first as usize;
                depth[c] = depth[i] + 1;
                depth[c + 1] = depth[i] + 1;
            }
        }
        let levels = depth.iter().max().map_or(0, |d| d + 1);
        let mut order = Vec::with_capacity(self.nodes.len());
        let mut bounds = vec![0u32];
        for d in (0..levels).rev() {
            order.extend((0..self.nodes.len() as u32).filter(|&i| depth[i as usize] == d));
            bounds.push(order.len() as u32);
        }
        (order, bounds)
    }

    /// Checks the layout invariants: node and primitive indices in range,
    /// children after their parents, every node reachable exactly once,
    /// every primitive in exactly one leaf, `1 <= count <= MAX_LEAF`, depth
    /// <= MAX_DEPTH, and bounds containing their children / primitives.
    pub fn validate(&self, aabbs: &[Aabb]) -> Result<(), String> {
        if self.nodes.is_empty() {
            return match (aabbs.len(), self.prim_indices.len()) {
                (0, 0) => Ok(()),
                (a, p) => Err(format!("no nodes but {a} primitives and {p} primitive indices")),
            };
        }
        if self.prim_indices.len() != aabbs.len() {
            return Err(format!(
                "{} primitive indices for {} primitives",
                self.prim_indices.len(),
                aabbs.len()
            ));
        }
        let mut visited = vec![false; self.nodes.len()];
        let mut seen = vec![0u32; aabbs.len()];
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            if std::mem::replace(&mut visited[i], true) {
                return Err(format!("node {i} reached twice"));
            }
            if depth > MAX_DEPTH {
                return Err(format!("node {i} at depth {depth} > {MAX_DEPTH}"));
            }
            let n = &self.nodes[i];
            let b = Bounds::of_node(n);
            let first = n.left_or_first as usize;
            if n.count == 0 {
                if first <= i || first + 1 >= self.nodes.len() {
                    return Err(format!("node {i}: children {first}, {} out of order or range", first + 1));
                }
                for c in [first, first + 1] {
                    if !b.contains(&Bounds::of_node(&self.nodes[c])) {
                        return Err(format!("node {i} does not contain its child {c}"));
                    }
                    stack.push((c, depth + 1));
                }
            } else {
                let end = first + n.count as usize;
                if n.count as usize > MAX_LEAF || end > self.prim_indices.len() {
                    return Err(format!("leaf {i}: primitives {first}..{end} too many or out of range"));
                }
                for &p in &self.prim_indices[first..end] {
                    let p = p as usize;
                    if p >= aabbs.len() {
                        return Err(format!("leaf {i}: primitive {p} out of range"));
                    }
                    seen[p] += 1;
                    if !b.contains(&Bounds::from_aabb(&aabbs[p])) {
                        return Err(format!("leaf {i} does not contain its primitive {p}"));
                    }
                }
            }
        }
        if let Some(i) = visited.iter().position(|v| !v) {
            return Err(format!("node {i} is unreachable"));
        }
        match seen.iter().position(|&c| c != 1) {
            Some(p) => Err(format!("primitive {p} referenced {} times", seen[p])),
            None => Ok(()),
        }
    }
}

fn extent(b: &Bounds) -> [f32; 3] {
    [b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]]
}

/// Bin origin and scale of `axis`: bin = (c - cmin) * scale.
#[inline(always)]
fn axis_scale(cb: &Bounds, axis: usize, nbins: usize) -> (f32, f32) {
    (cb.min[axis], nbins as f32 / (cb.max[axis] - cb.min[axis]))
}

/// Leaf, SAH split or median split for the node of `task` over `prims`.
fn decide(prims: &[u32], boxes: &[Bounds], centroids: &[[f32; 3]], bounds: &Bounds, task: &Task) -> Decision {
    let count = prims.len();
    if count <= 1 {
        return Decision::Leaf;
    }
    // (cost, axis, bin, left, right, left count)
    let mut best: Option<(f32, usize, usize, Bounds, Bounds, usize)> = None;
    let ext = extent(&task.cb);
    // Bin on all three axes in one pass over the primitives (each box and
    // centroid is read once); axes without centroid extent are ignored.
    let nbins = bin_count(count);
    let mut bins = [[EMPTY_BIN; BINS]; 3];
    let (mut cmin, mut scale) = ([0.0; 3], [0.0; 3]);
    for a in 0..3 {
        (cmin[a], scale[a]) = axis_scale(&task.cb, a, nbins);
    }
    for &p in prims {
        let (c, b) = (&centroids[p as usize], &boxes[p as usize]);
        for axis in 0..3 {
            let bin = &mut bins[axis][bin_of(c[axis], cmin[axis], scale[axis], nbins)];
            bin.count += 1;
            bin.bounds.grow(b);
        }
    }
    for (axis, bins) in bins.iter().enumerate() {
        // Also skips NaN and infinite extents.
        if !(ext[axis] > 0.0 && ext[axis].is_finite()) {
            continue;
        }
        // Suffix sweep: bounds/count right of each plane, then prefix sweep.
        let mut right = [Bounds::EMPTY; BINS];
        let mut right_count = [0usize; BINS];
        let (mut acc, mut n) = (Bounds::EMPTY, 0);
        for i in (1..nbins).rev() {
            acc.grow(&bins[i].bounds);
            n += bins[i].count as usize;
            right[i] = acc;
            right_count[i] = n;
        }
        let (mut acc, mut n) = (Bounds::EMPTY, 0);
        for i in 0..nbins - 1 {
            acc.grow(&bins[i].bounds);
            n += bins[i].count as usize;
            if n == 0 || n == count {
                continue;
            }
            let cost = acc.area() * n as f32 + right[i + 1].area() * right_count[i + 1] as f32;
            if best.as_ref().is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i, acc, right[i + 1], n));
            }
        }
    }
    let Some((cost, axis, bin, left, right, left_count)) = best else {
        // All centroids coincide: no plane separates them.
        return if count <= MAX_LEAF { Decision::Leaf } else { Decision::Median };
    };
    if count <= MAX_LEAF {
        let parent_area = bounds.area();
        let split_cost = if parent_area > 0.0 {
            TRAVERSAL_COST + INTERSECTION_COST * cost / parent_area
        } else {
            TRAVERSAL_COST + INTERSECTION_COST * count as f32 // flat/point node: no gain from splitting
        };
        if INTERSECTION_COST * count as f32 <= split_cost {
            return Decision::Leaf;
        }
    }
    // Keep room for a balanced subtree under each child (MAX_DEPTH).
    let child_depth = task.depth + 1;
    if child_depth + levels_needed(left_count.max(count - left_count)) > MAX_DEPTH {
        return if count <= MAX_LEAF { Decision::Leaf } else { Decision::Median };
    }
    Decision::Sah { axis, bin, left, right }
}

/// One object-space box per triangle (`indices.len() / 3` boxes).
pub fn triangle_aabbs(vertices: &[Vertex], indices: &[u32]) -> Vec<Aabb> {
    indices
        .chunks_exact(3)
        .map(|t| {
            let p0 = Vec3::from(vertices[t[0] as usize].position);
            let p1 = Vec3::from(vertices[t[1] as usize].position);
            let p2 = Vec3::from(vertices[t[2] as usize].position);
            Aabb { min: p0.min(p1).min(p2), max: p0.max(p1).max(p2) }
        })
        .collect()
}

/// World-space boxes of `scene.instances` (one per instance, in order): the
/// primitive's object-space bounds through the instance's world matrix. A
/// top level is `Bvh::build(&instance_aabbs(scene))`; its leaves then hold
/// instance indices. Instances of empty primitives get `Aabb::EMPTY`.
pub fn instance_aabbs(scene: &Scene) -> Vec<Aabb> {
    scene
        .instances
        .iter()
        .map(|i| scene.meshes[i.mesh].primitives[i.primitive].bounds.transformed(&i.world))
        .collect()
}

#[cfg(test)]
mod tests {
    use std::time::Instant;

    use super::*;
    use crate::accel::watertight::{traverse_closest, triangle_positions};
    use crate::scene::primitives::uv_sphere;

    struct Rng(u64);
    impl Rng {
        fn f(&mut self) -> f32 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
        fn v(&mut self) -> Vec3 {
            Vec3::new(self.f(), self.f(), self.f())
        }
    }

    fn tri_aabbs(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
        tris.iter().map(|t| Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) }).collect()
    }

    fn soup(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut r = Rng(seed);
        (0..n)
            .map(|_| {
                let c = r.v() * 100.0;
                [c + r.v() * 4.0 - 2.0, c + r.v() * 4.0 - 2.0, c + r.v() * 4.0 - 2.0]
            })
            .collect()
    }

    /// `n` x `n` quads over [0, size]^2 in XZ, heights with some noise.
    fn noisy_grid(n: usize, size: f32, seed: u64) -> Vec<[Vec3; 3]> {
        let mut r = Rng(seed);
        let h: Vec<f32> = (0..(n + 1) * (n + 1)).map(|_| r.f() * 0.3 * size / n as f32).collect();
        let p = |i: usize, j: usize| {
            Vec3::new(i as f32 * size / n as f32, h[i * (n + 1) + j], j as f32 * size / n as f32)
        };
        let mut tris = Vec::with_capacity(2 * n * n);
        for i in 0..n {
            for j in 0..n {
                tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        tris
    }

    fn check(aabbs: &[Aabb]) -> Bvh {
        let bvh = Bvh::build(aabbs);
        bvh.validate(aabbs).unwrap();
        for (i, n) in bvh.nodes.iter().enumerate() {
            if n.count == 0 {
                assert!(n.left_or_first as usize > i, "children after parents");
            } else {
                assert!(n.count as usize <= MAX_LEAF);
            }
        }
        assert!(bvh.depth() <= MAX_DEPTH);
        bvh
    }

    #[test]
    fn layout_matches_the_shader() {
        assert_eq!(std::mem::size_of::<BvhNode>(), 32);
        assert_eq!(std::mem::offset_of!(BvhNode, min), 0);
        assert_eq!(std::mem::offset_of!(BvhNode, left_or_first), 12);
        assert_eq!(std::mem::offset_of!(BvhNode, max), 16);
        assert_eq!(std::mem::offset_of!(BvhNode, count), 28);
    }

    #[test]
    fn random_soups_are_valid() {
        for (n, seed) in [(1, 1), (2, 2), (3, 3), (5, 7), (17, 4), (1000, 5), (20000, 6)] {
            let a = tri_aabbs(&soup(n, seed));
            let bvh = check(&a);
            assert!(bvh.sah_cost() > 0.0);
            if n == 1 {
                assert_eq!(bvh.nodes.len(), 1);
                assert_eq!((bvh.nodes[0].left_or_first, bvh.nodes[0].count), (0, 1));
            }
        }
        let empty = Bvh::build(&[]);
        assert!(empty.nodes.is_empty() && empty.prim_indices.is_empty());
        empty.validate(&[]).unwrap();
        assert_eq!((empty.depth(), empty.sah_cost()), (0, 0.0));
    }

    #[test]
    fn grid_and_sphere_are_valid() {
        let grid = noisy_grid(64, 10.0, 9);
        let bvh = check(&tri_aabbs(&grid));
        eprintln!("grid: {} tris, SAH {:.2}, depth {}", grid.len(), bvh.sah_cost(), bvh.depth());
        let p = uv_sphere(1.0, 64, 32);
        let a = triangle_aabbs(&p.vertices, &p.indices);
        let bvh = check(&a);
        eprintln!("sphere: {} tris, SAH {:.2}, depth {}", a.len(), bvh.sah_cost(), bvh.depth());
    }

    #[test]
    fn degenerate_inputs_still_build() {
        // All identical triangles (coincident centroids).
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        for n in [1, 2, 3, 4, 5, 8, 1000] {
            let bvh = check(&tri_aabbs(&vec![t; n]));
            assert!(bvh.depth() <= levels_needed(n) + 1);
        }
        // Identical point boxes.
        let b = Aabb { min: Vec3::ONE, max: Vec3::ONE };
        let bvh = check(&vec![b; 1000]);
        assert_eq!(bvh.sah_cost(), 0.0);
        // Zero-area triangles: collinear and single points, on a line.
        let tris: Vec<[Vec3; 3]> = (0..500)
            .map(|i| {
                let p = Vec3::splat(i as f32 * 0.01);
                if i % 2 == 0 {
                    [p, p + Vec3::X, p + 2.0 * Vec3::X]
                } else {
                    [p, p, p]
                }
            })
            .collect();
        check(&tri_aabbs(&tris));
        // Two triangles; one and two at the same place.
        check(&tri_aabbs(&[t, [Vec3::Z, Vec3::Z + Vec3::X, Vec3::Z + Vec3::Y]]));
        check(&tri_aabbs(&[t, t]));
        // Empty boxes mixed in (an instance of an empty primitive).
        let mut a = tri_aabbs(&soup(50, 3));
        a.extend([Aabb::EMPTY; 7]);
        check(&a);
    }

    #[test]
    fn depth_is_bounded_on_skewed_input() {
        // Exponentially spaced primitives: SAH alone peels off few at a time.
        let a: Vec<Aabb> = (0..5000)
            .map(|i| {
                let x = 1.002f32.powi(i);
                Aabb { min: Vec3::new(x, 0.0, 0.0), max: Vec3::new(x * 1.001, 1.0, 1.0) }
            })
            .collect();
        let bvh = check(&a);
        eprintln!("skewed: depth {}", bvh.depth());
    }

    #[test]
    fn levels_put_children_before_parents() {
        let p = uv_sphere(1.0, 24, 12);
        let bvh = check(&tri_aabbs(&triangle_positions(&p.vertices, &p.indices)));
        let (order, levels) = bvh.levels();
        assert_eq!(levels.len(), bvh.depth() + 1);
        assert_eq!(order.len(), bvh.nodes.len());
        assert_eq!(*order.last().unwrap(), 0, "the root is the last level");
        let mut rank = vec![usize::MAX; bvh.nodes.len()];
        for (r, &n) in order.iter().enumerate() {
            assert_eq!(rank[n as usize], usize::MAX, "node {n} listed twice");
            rank[n as usize] = r;
        }
        for (i, n) in bvh.nodes.iter().enumerate().filter(|(_, n)| n.count == 0) {
            let c = n.left_or_first as usize;
            assert!(rank[c] < rank[i] && rank[c + 1] < rank[i], "node {i} comes before its children");
        }
    }

    #[test]
    fn refit_matches_a_fresh_build() {
        let p = uv_sphere(1.0, 48, 24);
        let mut tris = triangle_positions(&p.vertices, &p.indices);
        let mut bvh = check(&tri_aabbs(&tris));
        // Move every vertex (a wobble plus a shift), then refit.
        let mut r = Rng(77);
        for t in &mut tris {
            for v in t.iter_mut() {
                *v = *v * (1.0 + 0.3 * v.y.sin()) + Vec3::new(2.0, 0.5, -1.0);
            }
            t[0] += (r.v() - 0.5) * 0.05;
        }
        let moved = tri_aabbs(&tris);
        bvh.refit(&moved);
        bvh.validate(&moved).unwrap();
        let fresh = check(&moved);
        let center = Vec3::new(2.0, 0.5, -1.0);
        let mut hits = 0;
        for _ in 0..2000 {
            let o = center + (r.v() - 0.5) * 8.0;
            let d = center + (r.v() - 0.5) * 1.5 - o;
            let a = traverse_closest(&bvh, &tris, o, d, f32::INFINITY);
            let b = traverse_closest(&fresh, &tris, o, d, f32::INFINITY);
            assert_eq!(a.map(|h| (h.0, h.1)), b.map(|h| (h.0, h.1)), "ray {o} {d}");
            hits += a.is_some() as usize;
        }
        assert!(hits > 1000, "{hits} hits");
    }

    /// ~1M triangles: build time and quality (release-like numbers need
    /// the dev profile's opt-level; see the eprintln).
    #[test]
    fn million_triangles_build_fast() {
        let tris = noisy_grid(707, 100.0, 42);
        let a = tri_aabbs(&tris);
        let t0 = Instant::now();
        let bvh = Bvh::build(&a);
        let s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let mut refitted = bvh.clone();
        refitted.refit(&a);
        let refit_s = t1.elapsed().as_secs_f64();
        assert_eq!(refitted.nodes, bvh.nodes);
        bvh.validate(&a).unwrap();
        eprintln!(
            "1M grid: {} tris in {:.3} s ({:.2} Mtri/s), {} nodes, SAH {:.2}, depth {}, refit {:.3} s",
            a.len(),
            s,
            a.len() as f64 / s / 1e6,
            bvh.nodes.len(),
            bvh.sah_cost(),
            bvh.depth(),
            refit_s
        );
        let p = uv_sphere(1.0, 1000, 500);
        let a = triangle_aabbs(&p.vertices, &p.indices);
        let t0 = Instant::now();
        let bvh = Bvh::build(&a);
        let s = t0.elapsed().as_secs_f64();
        bvh.validate(&a).unwrap();
        eprintln!(
            "1M sphere: {} tris in {:.3} s ({:.2} Mtri/s), SAH {:.2}, depth {}",
            a.len(),
            s,
            a.len() as f64 / s / 1e6,
            bvh.sah_cost(),
            bvh.depth()
        );
    }

    #[test]
    fn sponza_builds_per_primitive_and_top_level() {
        let path =
            concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/assets/scenes/SponzaCapsaicin/Sponza.gltf");
        if !std::path::Path::new(path).exists() {
            eprintln!("skipping: {path} not found");
            return;
        }
        let t0 = Instant::now();
        let scene = Scene::load(std::path::Path::new(path)).unwrap();
        let load_s = t0.elapsed().as_secs_f64();
        let (mut tris, mut secs, mut weighted_sah, mut depth, mut largest, mut blases) =
            (0usize, 0.0f64, 0.0f64, 0, 0, 0);
        for mesh in &scene.meshes {
            for p in &mesh.primitives {
                if p.indices.len() < 3 {
                    continue;
                }
                let a = triangle_aabbs(&p.vertices, &p.indices);
                let t = Instant::now();
                let bvh = Bvh::build(&a);
                secs += t.elapsed().as_secs_f64();
                bvh.validate(&a).unwrap();
                tris += a.len();
                largest = largest.max(a.len());
                weighted_sah += bvh.sah_cost() as f64 * a.len() as f64;
                depth = depth.max(bvh.depth());
                blases += 1;
            }
        }
        let inst = instance_aabbs(&scene);
        let tlas = Bvh::build(&inst);
        tlas.validate(&inst).unwrap();
        assert!(tris > 100_000);
        eprintln!(
            "Sponza: loaded in {load_s:.2} s; {blases} BLASes, {tris} tris (largest {largest}; {} instanced) \
             in {secs:.3} s ({:.2} Mtri/s), triangle-weighted SAH {:.2}, max depth {depth}; \
             top level over {} instances: SAH {:.2}, depth {}",
            scene.triangle_count(),
            tris as f64 / secs / 1e6,
            weighted_sah / tris as f64,
            inst.len(),
            tlas.sah_cost(),
            tlas.depth()
        );
    }
}
