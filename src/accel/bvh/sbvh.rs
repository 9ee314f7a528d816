//! Split BVH (Stich, Friedrich, Dietrich 2009, "Spatial Splits in Bounding
//! Volume Hierarchies") over triangles, into the same flat binary layout as
//! the binned builder (parent module docs), for static geometry.
//!
//! Per node: a full-sweep object split (references sorted by centroid on
//! each axis, every position evaluated) and, when the two object children
//! overlap by more than `alpha` of the root's surface area, a binned spatial
//! split ([`SPATIAL_BINS`] slabs per axis, each triangle clipped to every
//! slab it crosses, so bin bounds hug the triangle's part inside the slab).
//! The cheaper of leaf / object / spatial wins; straddling references of a
//! spatial split are "unsplit" (kept whole on one side) when that is cheaper.
//! With `alpha = None` no spatial split is tried: that is the full-sweep SAH
//! binary BVH, the reference quality for the binned builder.
//!
//! Differences from [`Bvh::build`]'s output: a triangle may be referenced
//! by several leaves (`prim_indices` repeats it), and a leaf's box holds
//! only the clipped part of its triangles, so the tree cannot be refit when
//! vertices move (skinned meshes keep the binned builder). Duplication is
//! capped at [`MAX_DUPLICATION`] times the triangle count.

use glam::Vec3;

use super::build::{levels_needed, Bounds};
use super::{Bvh, BvhNode, INTERSECTION_COST, MAX_DEPTH, MAX_LEAF, TRAVERSAL_COST};

/// Spatial-split slabs per axis, at most; small nodes use fewer (one per
/// reference, at least 8): their references span most of the node, so
/// clipping them into every slab dominated the build (about 2x faster on
/// Sponza than 32 everywhere, SAH cost within 0.1%).
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
        let n = tris.len();
        let mut stats = SbvhStats::default();
        if n == 0 {
            return (Bvh::default(), stats);
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
        let min_overlap = match alpha {
            Some(a) if root_area > 0.0 && root_area.is_finite() => Some(a * root_area),
            _ => None,
        };
        let mut budget = ((n as f32 * MAX_DUPLICATION) as usize).saturating_sub(n);
        let mut nodes: Vec<BvhNode> = vec![to_node(&root, 0, 0)];
        let mut prims: Vec<u32> = Vec::with_capacity(n);
        let mut stack = vec![Task { node: 0, depth: 1, refs }];
        while let Some(Task { node, depth, mut refs }) = stack.pop() {
            let bounds = Bounds { min: nodes[node].min, max: nodes[node].max };
            let count = refs.len();
            let (left, right) = match split(&mut refs, &bounds, tris, depth, min_overlap, budget) {
                None => {
                    nodes[node].left_or_first = prims.len() as u32;
                    nodes[node].count = count as u32;
                    prims.extend(refs.iter().map(|r| r.prim));
                    continue;
                }
                Some((l, r, spatial)) => {
                    if spatial {
                        stats.spatial_splits += 1;
                    } else {
                        stats.object_splits += 1;
                    }
                    (l, r)
                }
            };
            budget = budget.saturating_sub((left.len() + right.len()).saturating_sub(count));
            let first = nodes.len();
            nodes.push(to_node(&union(&left), 0, 0));
            nodes.push(to_node(&union(&right), 0, 0));
            nodes[node].left_or_first = first as u32;
            nodes[node].count = 0;
            stack.push(Task { node: first + 1, depth: depth + 1, refs: right });
            stack.push(Task { node: first, depth: depth + 1, refs: left });
        }
        stats.references = prims.len();
        nodes.shrink_to_fit();
        (Bvh { nodes, prim_indices: prims }, stats)
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

/// Splits the part of `tri` inside `r` at the plane `axis = pos`: boxes of
/// the triangle's parts below and above it, each within `r`. Intersection
/// points are padded by a few ulps off the split axis so float rounding never
/// leaves a sliver of the triangle outside both boxes.
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
