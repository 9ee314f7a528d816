//! The builder: top-down binned SAH over all three axes, with object-median
//! fallbacks, into the flat node layout described in the parent module.

use super::{Bvh, BvhNode, BINS, INTERSECTION_COST, MAX_DEPTH, MAX_LEAF, TRAVERSAL_COST};
use crate::scene::Aabb;

/// Plain-array box used by the builder (cheap component access at the
/// crate's opt-level 1).
#[derive(Clone, Copy, Debug)]
pub(super) struct Bounds {
    pub(super) min: [f32; 3],
    pub(super) max: [f32; 3],
}

impl Bounds {
    pub(super) const EMPTY: Bounds = Bounds { min: [f32::INFINITY; 3], max: [f32::NEG_INFINITY; 3] };

    #[inline(always)]
    pub(super) fn from_aabb(b: &Aabb) -> Bounds {
        Bounds { min: b.min.to_array(), max: b.max.to_array() }
    }

    #[inline(always)]
    pub(super) fn of_node(n: &BvhNode) -> Bounds {
        Bounds { min: n.min, max: n.max }
    }

    #[inline(always)]
    pub(super) fn grow(&mut self, b: &Bounds) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(b.min[k]);
            self.max[k] = self.max[k].max(b.max[k]);
        }
    }

    #[inline(always)]
    pub(super) fn grow_point(&mut self, p: &[f32; 3]) {
        for (k, &c) in p.iter().enumerate() {
            self.min[k] = self.min[k].min(c);
            self.max[k] = self.max[k].max(c);
        }
    }

    /// Surface area; 0 for empty (inverted) boxes.
    #[inline(always)]
    pub(super) fn area(&self) -> f32 {
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

    pub(super) fn contains(&self, inner: &Bounds) -> bool {
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
pub(super) fn levels_needed(count: usize) -> usize {
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
