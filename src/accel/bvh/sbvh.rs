//! Split BVH (Stich, Friedrich, Dietrich 2009) over triangles for static geometry, in the binned
//! builder's flat binary layout.
//!
//! Per node: a full-sweep object split and, when its children overlap by more than `alpha` of the root
//! area, a binned spatial split ([`SPATIAL_BINS`] slabs, triangles clipped to each slab they cross so
//! bin bounds hug them). Cheapest of leaf / object / spatial wins; straddlers are "unsplit" (kept
//! whole on one side) when cheaper. `alpha = None` gives the full-sweep SAH BVH, the binned builder's
//! quality reference.
//!
//! Unlike [`Bvh::build`]'s output, a triangle may be in several leaves and a leaf's box holds only
//! clipped parts, so the tree cannot be refit (skinned meshes keep the binned builder). Duplication
//! is capped at [`MAX_DUPLICATION`] times the triangle count.

use glam::Vec3;

use super::build::{levels_needed, Bounds};
use super::{Bvh, BvhNode, INTERSECTION_COST, MAX_DEPTH, MAX_LEAF, TRAVERSAL_COST};

/// Most slabs per axis; small nodes use fewer (one per reference, at least 8): their references span
/// most of the node, so clipping into every slab dominated the build (~2x faster on Sponza, SAH within
/// 0.1%).
pub const SPATIAL_BINS: usize = 32;
/// Stich et al.'s overlap threshold: spatial splits are tried where the
/// object split's children overlap by more than this share of the root
/// area (1e-5 in the paper).
pub const DEFAULT_ALPHA: f32 = 1e-5;
/// References allowed in total, as a multiple of the triangle count: bounds
/// memory and build time on pathological inputs.
pub const MAX_DUPLICATION: f32 = 2.0;

#[derive(Clone, Copy, Debug)]
struct Ref {
    prim: u32,
    b: Bounds,
}

struct Task {
    node: usize,
    depth: usize,
    refs: Vec<Ref>,
}

/// Statistics of one build (for the quality report and logs).
#[derive(Clone, Copy, Debug, Default)]
pub struct SbvhStats {
    pub spatial_splits: usize,
    pub object_splits: usize,
    pub references: usize,
}

impl Bvh {
    /// SBVH over `tris` with overlap threshold `alpha` (relative to the
    /// root area); `None` builds the full-sweep object-split SAH BVH.
    pub fn build_sbvh(tris: &[[Vec3; 3]], alpha: Option<f32>) -> Bvh {
        Self::build_sbvh_stats(tris, alpha).0
    }

    pub fn build_sbvh_stats(tris: &[[Vec3; 3]], alpha: Option<f32>) -> (Bvh, SbvhStats) {
        Self::build_sbvh_in(tris, alpha, PAR_MIN_REFS)
    }

    /// The build, on every core for inputs of at least `par_min` triangles.
    pub(super) fn build_sbvh_in(tris: &[[Vec3; 3]], alpha: Option<f32>, par_min: usize) -> (Bvh, SbvhStats) {
        let n = tris.len();
        let mut b = Build {
            tris,
            min_overlap: None,
            nodes: Vec::new(),
            prims: Vec::new(),
            stats: Default::default(),
        };
        if n == 0 {
            return (Bvh::default(), b.stats);
        }
        assert!(n < (u32::MAX / 4) as usize, "SBVH over {n} triangles: indices overflow u32");
        let refs: Vec<Ref> = tris
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let mut b = Bounds::EMPTY;
                for v in t {
                    b.grow_point(&v.to_array());
                }
                Ref { prim: i as u32, b }
            })
            .collect();
        let root = union(&refs);
        let root_area = root.area();
        // Spatial splits need a finite box with area to bin over.
        b.min_overlap = match alpha {
            Some(a) if root_area > 0.0 && root_area.is_finite() => Some(a * root_area),
            _ => None,
        };
        let mut budget = ((n as f32 * MAX_DUPLICATION) as usize).saturating_sub(n);
        b.nodes.push(to_node(&root, 0, 0));
        let root = Task { node: 0, depth: 1, refs };
        if n < par_min {
            b.grow(vec![root], &mut budget);
        } else {
            b.grow_parallel(root, budget);
        }
        b.stats.references = b.prims.len();
        b.nodes.shrink_to_fit();
        (Bvh { nodes: b.nodes, prim_indices: b.prims }, b.stats)
    }
}

/// Inputs of at least this many triangles build on every core (a flattened
/// Sponza, ~330k references, took 5 s on one).
const PAR_MIN_REFS: usize = 1 << 16;
/// Serial splits until this many subtrees remain, then built on the cores. Fixed, not the core count,
/// so the tree does not depend on the machine.
const PAR_SUBTREES: usize = 16;

/// One build's output so far.
struct Build<'a> {
    tris: &'a [[Vec3; 3]],
    min_overlap: Option<f32>,
    nodes: Vec<BvhNode>,
    prims: Vec<u32>,
    stats: SbvhStats,
}

impl Build<'_> {
    /// Splits `task` (or makes it a leaf: None) within the duplication
    /// `budget`, which it draws down.
    fn step(&mut self, task: Task, budget: &mut usize) -> Option<(Task, Task)> {
        let Task { node, depth, mut refs } = task;
        let bounds = Bounds { min: self.nodes[node].min, max: self.nodes[node].max };
        let count = refs.len();
        let Some((left, right, spatial)) =
            split(&mut refs, &bounds, self.tris, depth, self.min_overlap, *budget)
        else {
            self.nodes[node].left_or_first = self.prims.len() as u32;
            self.nodes[node].count = count as u32;
            self.prims.extend(refs.iter().map(|r| r.prim));
            return None;
        };
        if spatial {
            self.stats.spatial_splits += 1;
        } else {
            self.stats.object_splits += 1;
        }
        *budget = budget.saturating_sub((left.len() + right.len()).saturating_sub(count));
        let first = self.nodes.len();
        self.nodes.push(to_node(&union(&left), 0, 0));
        self.nodes.push(to_node(&union(&right), 0, 0));
        self.nodes[node].left_or_first = first as u32;
        self.nodes[node].count = 0;
        Some((
            Task { node: first, depth: depth + 1, refs: left },
            Task { node: first + 1, depth: depth + 1, refs: right },
        ))
    }

    /// Builds the subtrees of `stack`'s tasks, depth first, left child first.
    fn grow(&mut self, mut stack: Vec<Task>, budget: &mut usize) {
        while let Some(task) = stack.pop() {
            if let Some((left, right)) = self.step(task, budget) {
                stack.push(right);
                stack.push(left);
            }
        }
    }

    /// Splits the largest task until [`PAR_SUBTREES`] remain and builds them in parallel, each with a
    /// size share of the budget. Same SAH choices as `grow`; only budget sharing and node order differ.
    fn grow_parallel(&mut self, root: Task, mut budget: usize) {
        let mut frontier = vec![root];
        while frontier.len() < PAR_SUBTREES {
            let Some((k, _)) =
                frontier.iter().enumerate().max_by_key(|(k, t)| (t.refs.len(), std::cmp::Reverse(*k)))
            else {
                break;
            };
            let task = frontier.remove(k);
            if let Some((left, right)) = self.step(task, &mut budget) {
                frontier.insert(k, right);
                frontier.insert(k, left);
            }
        }
        let total: usize = frontier.iter().map(|t| t.refs.len()).sum::<usize>().max(1);
        let mut size_order: Vec<usize> = (0..frontier.len()).collect();
        size_order.sort_by_key(|&k| std::cmp::Reverse(frontier[k].refs.len()));
        let tasks: Vec<std::sync::Mutex<Option<Task>>> =
            frontier.into_iter().map(|t| std::sync::Mutex::new(Some(t))).collect();
        let (tris, min_overlap, nodes) = (self.tris, self.min_overlap, &self.nodes);
        let subtrees = crate::par::map(tasks.len(), &size_order, |k| {
            let task =
                tasks[k].lock().map(|mut t| t.take()).ok().flatten().expect("each subtree is built once");
            let at = task.node;
            let mut share = (budget as u128 * task.refs.len() as u128 / total as u128) as usize;
            let mut sub = Build {
                tris,
                min_overlap,
                nodes: vec![nodes[at]],
                prims: Vec::new(),
                stats: Default::default(),
            };
            sub.grow(vec![Task { node: 0, ..task }], &mut share);
            (at, sub)
        })
        .unwrap_or_else(|e| panic!("SBVH build: {e}"));
        for (at, sub) in subtrees {
            // Subtree node i > 0 lands at base + i - 1; its leaves' first
            // reference moves by the references already placed.
            let (base, first) = (self.nodes.len() as u32, self.prims.len() as u32);
            let link = |mut n: BvhNode| {
                if n.count == 0 {
                    n.left_or_first = base + n.left_or_first - 1;
                } else {
                    n.left_or_first += first;
                }
                n
            };
            self.nodes[at] = link(sub.nodes[0]);
            self.nodes.extend(sub.nodes[1..].iter().map(|&n| link(n)));
            self.prims.extend(sub.prims);
            self.stats.spatial_splits += sub.stats.spatial_splits;
            self.stats.object_splits += sub.stats.object_splits;
        }
    }
}

fn to_node(b: &Bounds, left_or_first: u32, count: u32) -> BvhNode {
    BvhNode { min: b.min, left_or_first, max: b.max, count }
}

fn union(refs: &[Ref]) -> Bounds {
    let mut b = Bounds::EMPTY;
    for r in refs {
        b.grow(&r.b);
    }
    b
}

fn centroid(b: &Bounds, axis: usize) -> f32 {
    0.5 * (b.min[axis] + b.max[axis])
}

fn intersect(a: &Bounds, b: &Bounds) -> Bounds {
    let mut r = *a;
    for k in 0..3 {
        r.min[k] = a.min[k].max(b.min[k]);
        r.max[k] = a.max[k].min(b.max[k]);
    }
    r
}

fn is_empty(b: &Bounds) -> bool {
    // NaN bounds count as empty too.
    (0..3).any(|k| b.min[k].partial_cmp(&b.max[k]).is_none_or(|o| o.is_gt()))
}

struct ObjectSplit {
    cost: f32,
    axis: usize,
    /// References `[0, at)` of the sorted order go left.
    at: usize,
    left: Bounds,
    right: Bounds,
}

fn sort_axis(refs: &mut [Ref], axis: usize) {
    refs.sort_unstable_by(|a, b| {
        centroid(&a.b, axis).total_cmp(&centroid(&b.b, axis)).then(a.prim.cmp(&b.prim))
    });
}

/// Best object split over all three axes (full sweep). Leaves `refs` in
/// arbitrary order. `count >= 2`, so a split position always exists.
fn best_object_split(refs: &mut [Ref]) -> ObjectSplit {
    let n = refs.len();
    let mut best =
        ObjectSplit { cost: f32::INFINITY, axis: 0, at: n / 2, left: Bounds::EMPTY, right: Bounds::EMPTY };
    let mut right_area = vec![0.0f32; n];
    for axis in 0..3 {
        sort_axis(refs, axis);
        let mut acc = Bounds::EMPTY;
        for i in (1..n).rev() {
            acc.grow(&refs[i].b);
            right_area[i] = acc.area();
        }
        let mut acc = Bounds::EMPTY;
        for i in 1..n {
            acc.grow(&refs[i - 1].b);
            let cost = acc.area() * i as f32 + right_area[i] * (n - i) as f32;
            if cost < best.cost {
                best.cost = cost;
                best.axis = axis;
                best.at = i;
            }
        }
    }
    if !best.cost.is_finite() {
        best.cost = f32::INFINITY;
    }
    sort_axis(refs, best.axis);
    best.left = union(&refs[..best.at]);
    best.right = union(&refs[best.at..]);
    best
}

/// Boxes of the parts of `tri` inside `r` below and above the plane `axis = pos`. Intersection points
/// are padded a few ulps off the split axis so rounding never leaves a sliver outside both boxes.
fn split_reference(tri: &[Vec3; 3], r: &Bounds, axis: usize, pos: f32) -> (Bounds, Bounds) {
    let (mut l, mut rt) = (Bounds::EMPTY, Bounds::EMPTY);
    for i in 0..3 {
        let (v0, v1) = (tri[i].to_array(), tri[(i + 1) % 3].to_array());
        let (a, b) = (v0[axis], v1[axis]);
        if a <= pos {
            l.grow_point(&v0);
        }
        if a >= pos {
            rt.grow_point(&v0);
        }
        if (a < pos && b > pos) || (a > pos && b < pos) {
            let t = ((pos - a) / (b - a)).clamp(0.0, 1.0);
            let mut lo = [0.0f32; 3];
            let mut hi = [0.0f32; 3];
            for k in 0..3 {
                let x = v0[k] + (v1[k] - v0[k]) * t;
                let pad = if k == axis {
                    0.0
                } else {
                    4.0 * f32::EPSILON * x.abs().max(v0[k].abs()).max(v1[k].abs())
                };
                (lo[k], hi[k]) = if k == axis { (pos, pos) } else { (x - pad, x + pad) };
            }
            for p in [&lo, &hi] {
                l.grow_point(p);
                rt.grow_point(p);
            }
        }
    }
    l.max[axis] = l.max[axis].min(pos);
    rt.min[axis] = rt.min[axis].max(pos);
    (intersect(&l, r), intersect(&rt, r))
}

struct SpatialSplit {
    cost: f32,
    axis: usize,
    pos: f32,
}

#[inline(always)]
fn bin_of(x: f32, min: f32, scale: f32, nbins: usize) -> usize {
    (((x - min) * scale) as usize).min(nbins - 1)
}

/// Best binned spatial split of a node with bounds `nb` (chopped-triangle
/// binning with entry/exit counts).
fn best_spatial_split(refs: &[Ref], nb: &Bounds, tris: &[[Vec3; 3]]) -> Option<SpatialSplit> {
    let mut best: Option<SpatialSplit> = None;
    let nbins = refs.len().clamp(8, SPATIAL_BINS);
    for axis in 0..3 {
        let ext = nb.max[axis] - nb.min[axis];
        if !(ext > 0.0 && ext.is_finite()) {
            continue;
        }
        let width = ext / nbins as f32;
        let scale = 1.0 / width;
        let mut bins = [Bounds::EMPTY; SPATIAL_BINS];
        let mut enter = [0u32; SPATIAL_BINS];
        let mut exit = [0u32; SPATIAL_BINS];
        for r in refs {
            let b0 = bin_of(r.b.min[axis], nb.min[axis], scale, nbins);
            let b1 = bin_of(r.b.max[axis], nb.min[axis], scale, nbins).max(b0);
            enter[b0] += 1;
            exit[b1] += 1;
            let mut cur = r.b;
            for (i, bin) in bins.iter_mut().enumerate().take(b1).skip(b0) {
                let plane = nb.min[axis] + width * (i + 1) as f32;
                let (l, rt) = split_reference(&tris[r.prim as usize], &cur, axis, plane);
                bin.grow(&l);
                cur = rt;
            }
            bins[b1].grow(&cur);
        }
        let mut right_area = [0.0f32; SPATIAL_BINS];
        let mut right_count = [0u32; SPATIAL_BINS];
        let (mut acc, mut c) = (Bounds::EMPTY, 0);
        for i in (1..nbins).rev() {
            acc.grow(&bins[i]);
            c += exit[i];
            right_area[i] = acc.area();
            right_count[i] = c;
        }
        let (mut acc, mut c) = (Bounds::EMPTY, 0);
        for i in 0..nbins - 1 {
            acc.grow(&bins[i]);
            c += enter[i];
            let rc = right_count[i + 1];
            if c == 0 || rc == 0 {
                continue;
            }
            let cost = acc.area() * c as f32 + right_area[i + 1] * rc as f32;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(SpatialSplit { cost, axis, pos: nb.min[axis] + width * (i + 1) as f32 });
            }
        }
    }
    best
}

/// Partitions `refs` at a spatial plane, splitting straddlers or keeping
/// them whole on one side when that is cheaper (reference unsplitting).
/// `None` if a side would be empty.
fn partition_spatial(refs: Vec<Ref>, s: &SpatialSplit, tris: &[[Vec3; 3]]) -> Option<(Vec<Ref>, Vec<Ref>)> {
    let (axis, pos) = (s.axis, s.pos);
    let (mut left, mut right, mut straddle) = (Vec::new(), Vec::new(), Vec::new());
    for r in refs {
        if r.b.max[axis] <= pos {
            left.push(r);
        } else if r.b.min[axis] >= pos {
            right.push(r);
        } else {
            straddle.push(r);
        }
    }
    let (mut lb, mut rb) = (union(&left), union(&right));
    for r in straddle {
        let (nl, nr) = (left.len() as f32, right.len() as f32);
        let (pl, pr) = split_reference(&tris[r.prim as usize], &r.b, axis, pos);
        let (mut sl, mut sr) = (lb, rb);
        sl.grow(&pl);
        sr.grow(&pr);
        let c_split = sl.area() * (nl + 1.0) + sr.area() * (nr + 1.0);
        let mut ul = lb;
        ul.grow(&r.b);
        let c_left = ul.area() * (nl + 1.0) + rb.area() * nr;
        let mut ur = rb;
        ur.grow(&r.b);
        let c_right = lb.area() * nl + ur.area() * (nr + 1.0);
        if c_left <= c_split && c_left <= c_right {
            lb = ul;
            left.push(r);
        } else if c_right <= c_split {
            rb = ur;
            right.push(r);
        } else {
            // A clipped part can vanish when the triangle only touches the plane.
            if !is_empty(&pl) {
                lb.grow(&pl);
                left.push(Ref { prim: r.prim, b: pl });
            }
            if !is_empty(&pr) {
                rb.grow(&pr);
                right.push(Ref { prim: r.prim, b: pr });
            }
        }
    }
    (!left.is_empty() && !right.is_empty()).then_some((left, right))
}

/// Leaf (`None`) or the two children and whether the split was spatial.
#[allow(clippy::type_complexity)]
fn split(
    refs: &mut Vec<Ref>,
    nb: &Bounds,
    tris: &[[Vec3; 3]],
    depth: usize,
    min_overlap: Option<f32>,
    budget: usize,
) -> Option<(Vec<Ref>, Vec<Ref>, bool)> {
    let count = refs.len();
    if count <= 1 {
        return None;
    }
    let parent_area = nb.area();
    let obj = best_object_split(refs);
    let mut best_cost = obj.cost;
    let mut spatial = None;
    if let Some(min_overlap) = min_overlap {
        let overlap = intersect(&obj.left, &obj.right);
        if !is_empty(&overlap) && overlap.area() > min_overlap && budget > 0 {
            if let Some(s) = best_spatial_split(refs, nb, tris) {
                if s.cost < best_cost {
                    best_cost = s.cost;
                    spatial = Some(s);
                }
            }
        }
    }
    if count <= MAX_LEAF {
        let split_cost = if parent_area > 0.0 && parent_area.is_finite() {
            TRAVERSAL_COST + INTERSECTION_COST * best_cost / parent_area
        } else {
            TRAVERSAL_COST + INTERSECTION_COST * count as f32
        };
        if INTERSECTION_COST * count as f32 <= split_cost {
            return None;
        }
    }
    let fits = |l: usize, r: usize| depth + 1 + levels_needed(l.max(r)) <= MAX_DEPTH;
    if let Some(s) = spatial {
        let taken = std::mem::take(refs);
        let backup = taken.clone();
        match partition_spatial(taken, &s, tris) {
            Some((l, r))
                if l.len() < count
                    && r.len() < count
                    && l.len() + r.len() - count <= budget
                    && fits(l.len(), r.len()) =>
            {
                return Some((l, r, true));
            }
            _ => {
                *refs = backup;
                // `refs` is back in the object split's sorted order.
            }
        }
    }
    if fits(obj.at, count - obj.at) {
        let right = refs.split_off(obj.at);
        return Some((std::mem::take(refs), right, false));
    }
    // Too deep for the SAH choice: object median on the largest axis.
    let ext: Vec<f32> = (0..3).map(|k| nb.max[k] - nb.min[k]).collect();
    let axis = if ext[0] >= ext[1] && ext[0] >= ext[2] {
        0
    } else if ext[1] >= ext[2] {
        1
    } else {
        2
    };
    sort_axis(refs, axis);
    let right = refs.split_off(count / 2);
    Some((std::mem::take(refs), right, false))
}
