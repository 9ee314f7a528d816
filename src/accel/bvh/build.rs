//! The builder: top-down binned SAH over all three axes, with object-median
//! fallbacks, into the flat node layout described in the parent module. Boxes
//! live in SIMD lanes (`Box4`: one `minps`/`maxps` per grow at the crate's
//! opt-level 1) and large inputs build on every core.

use glam::{Vec3, Vec4};

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

    pub(super) fn contains(&self, inner: &Bounds) -> bool {
        let empty = (0..3).any(|k| inner.min[k] > inner.max[k]);
        empty || (0..3).all(|k| self.min[k] <= inner.min[k] && self.max[k] >= inner.max[k])
    }

    fn to_node(self, left_or_first: u32, count: u32) -> BvhNode {
        BvhNode { min: self.min, left_or_first, max: self.max, count }
    }
}

/// A box in SIMD lanes (x, y, z; w is not a coordinate). An empty box is inverted.
#[derive(Clone, Copy, Debug)]
struct Box4 {
    lo: Vec4,
    hi: Vec4,
}

impl Box4 {
    const EMPTY: Box4 = Box4 { lo: Vec4::splat(f32::INFINITY), hi: Vec4::splat(f32::NEG_INFINITY) };

    #[inline(always)]
    fn grow(&mut self, b: &Box4) {
        self.lo = self.lo.min(b.lo);
        self.hi = self.hi.max(b.hi);
    }

    #[inline(always)]
    fn grow_point(&mut self, p: Vec4) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    /// Half the surface area of a box known not to be empty (an empty one gives inf or NaN).
    #[inline(always)]
    fn half_area_unchecked(&self) -> f32 {
        let d = self.hi - self.lo;
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    fn bounds(&self) -> Bounds {
        Bounds { min: self.lo.truncate().to_array(), max: self.hi.truncate().to_array() }
    }
}

/// A primitive's box, moved with it by every partition so each level streams through one array
/// (32 bytes: the primitive's index rides in `lo.w`, which no result is read from).
#[derive(Clone, Copy)]
struct Ref(Box4);

/// Added to a primitive index to make `lo.w`'s bits: a normal float in [1, f32::MAX] for every index
/// below 2^30. The raw index would be a denormal, and every sum and difference the w lane goes through
/// would take a microcode assist (a third of the build's time).
const PRIM_BITS: u32 = 0x3f80_0000;

impl Ref {
    #[inline(always)]
    fn new(b: &Aabb, prim: u32) -> Ref {
        Ref(Box4 { lo: b.min.extend(f32::from_bits(prim + PRIM_BITS)), hi: b.max.extend(0.0) })
    }

    #[inline(always)]
    fn prim(&self) -> u32 {
        self.0.lo.w.to_bits() - PRIM_BITS
    }

    /// Twice the centroid (the bins scale it away; saves a multiply per reference and level).
    #[inline(always)]
    fn centroid2(&self) -> Vec4 {
        self.0.lo + self.0.hi
    }
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Box4,
    count: u32,
}

const EMPTY_BIN: Bin = Bin { bounds: Box4::EMPTY, count: 0 };

/// Per-thread working memory of `decide`, reused from node to node (filling fresh arrays per node
/// was a fifth of the build).
struct Scratch {
    bins: [[Bin; BINS]; 3],
    /// Per plane: half the area of the boxes right of it times their count.
    right_cost: [f32; BINS],
}

impl Scratch {
    fn new() -> Box<Scratch> {
        Box::new(Scratch { bins: [[EMPTY_BIN; BINS]; 3], right_cost: [0.0; BINS] })
    }
}

/// Bins of doubled centroid coordinates on all three axes: bin = (c - origin) * scale, clamped.
/// Used for both binning and partitioning, so the two always agree (a chosen split never leaves a
/// side empty). NaN lands in bin 0.
#[derive(Clone, Copy)]
struct Binning {
    origin: Vec4,
    scale: Vec4,
    /// The last bin, as a float (the clamp happens before the conversion).
    last: Vec4,
}

impl Binning {
    /// Over the doubled-centroid bounds `cb`, `nbins` bins per axis.
    fn new(cb: &Box4, nbins: usize) -> Binning {
        let scale = Vec4::splat(nbins as f32) / (cb.hi - cb.lo);
        Binning { origin: cb.lo, scale, last: Vec4::splat((nbins - 1) as f32) }
    }

    /// Partitions `refs` into those whose centroid's bin on axis `A` is at most `bin` (< the last)
    /// and the rest; returns the left count and both sides' centroid bounds. The test is `bins`' float
    /// operations on one lane, compared instead of converted: trunc(clamp(t, 0, last)) <= bin is
    /// !(t >= bin + 1), NaN going left in both. The axis is a constant so the lane is not a jump.
    fn partition<const A: usize>(&self, refs: &mut [Ref], bin: usize) -> (usize, Box4, Box4) {
        let (origin, scale, limit) = (self.origin[A], self.scale[A], (bin + 1) as f32);
        // Negated on purpose: NaN must go left, as its bin (0) does.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let left = |c: Vec4| !((c[A] - origin) * scale >= limit);
        let (mut lcb, mut rcb) = (Box4::EMPTY, Box4::EMPTY);
        // Hoare's scheme: each reference classified once, only misplaced pairs swapped.
        let (mut i, mut j) = (0, refs.len());
        loop {
            while i < j && left(refs[i].centroid2()) {
                lcb.grow_point(refs[i].centroid2());
                i += 1;
            }
            while i < j && !left(refs[j - 1].centroid2()) {
                rcb.grow_point(refs[j - 1].centroid2());
                j -= 1;
            }
            if i == j {
                break;
            }
            // refs[i] goes right, refs[j - 1] left.
            rcb.grow_point(refs[i].centroid2());
            lcb.grow_point(refs[j - 1].centroid2());
            refs.swap(i, j - 1);
            i += 1;
            j -= 1;
        }
        (i, lcb, rcb)
    }

    /// The bins of centroid `c` on x, y and z. Clamped in float, then converted in one SIMD
    /// instruction: the per-lane saturating `as usize` casts were a third of the binning.
    #[inline(always)]
    fn bins(&self, c: Vec4) -> [usize; 3] {
        // max(NaN, 0) is 0 with SSE's operand order (and the scalar f32::max).
        let t = ((c - self.origin) * self.scale).max(Vec4::ZERO).min(self.last);
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{__m128, _mm_cvtsi128_si32, _mm_cvttps_epi32, _mm_shuffle_epi32};
            // SAFETY: SSE2 is part of every x86_64 target; the lanes are in [0, last].
            unsafe {
                let v = _mm_cvttps_epi32(__m128::from(t));
                let lane = |x| _mm_cvtsi128_si32(x) as usize;
                [lane(v), lane(_mm_shuffle_epi32::<0b01>(v)), lane(_mm_shuffle_epi32::<0b10>(v))]
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let last = self.last.x as usize;
            [(t.x as usize).min(last), (t.y as usize).min(last), (t.z as usize).min(last)]
        }
    }
}

/// Bins used for a node of `count` primitives: fewer for small nodes,
/// whose fixed binning cost would otherwise dominate the build.
#[inline(always)]
fn bin_count(count: usize) -> usize {
    count.clamp(4, BINS)
}

/// Levels a balanced subtree over `count` primitives needs below its root.
pub(super) fn levels_needed(count: usize) -> usize {
    let leaves = count.div_ceil(MAX_LEAF);
    (usize::BITS - leaves.saturating_sub(1).leading_zeros()) as usize // ceil(log2(leaves))
}

struct Task {
    node: usize,
    /// The task's references: `refs[first .. first + count]` of the whole build.
    first: usize,
    count: usize,
    depth: usize,
    /// Bounds of the primitives' doubled centroids.
    cb: Box4,
}

enum Decision {
    Leaf,
    /// SAH plane: primitives whose bin on `axis` is <= `bin` go left.
    Sah {
        axis: usize,
        bin: usize,
        left: Box4,
        right: Box4,
    },
    /// Object median along the largest centroid axis.
    Median,
}

/// Builds of at least this many primitives run on every core (below it, thread start-up is as dear
/// as the build).
const PAR_MIN_PRIMS: usize = 1 << 15;
/// Serial splits (binning on every core) until this many subtrees remain, then each subtree on a
/// core. Fixed, not the core count, so the tree does not depend on the machine.
const PAR_SUBTREES: usize = 32;
/// Nodes of at least twice this many primitives bin in parallel chunks of this size.
const PAR_BIN_CHUNK: usize = 1 << 16;

impl Bvh {
    /// Builds over `aabbs` (one per primitive). Empty input gives an empty
    /// BVH (no nodes): callers skip such primitives.
    pub fn build(aabbs: &[Aabb]) -> Bvh {
        Self::build_in(aabbs, PAR_MIN_PRIMS)
    }

    /// [`Bvh::build`] over the triangles' boxes, without a list of them.
    pub fn build_triangles(tris: &[[Vec3; 3]]) -> Bvh {
        let refs = collect_refs(tris.len(), PAR_MIN_PRIMS, |i| {
            let t = &tris[i];
            Ref::new(&Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) }, i as u32)
        });
        Self::build_refs(refs, PAR_MIN_PRIMS)
    }

    /// The build, on every core for inputs of at least `par_min` primitives. The tree is the same
    /// either way.
    pub(super) fn build_in(aabbs: &[Aabb], par_min: usize) -> Bvh {
        Self::build_refs(aabbs.iter().enumerate().map(|(i, a)| Ref::new(a, i as u32)).collect(), par_min)
    }

    fn build_refs(mut refs: Vec<Ref>, par_min: usize) -> Bvh {
        let n = refs.len();
        if n == 0 {
            return Bvh::default();
        }
        // Below 2^30: node indices fit u32, and a primitive index fits `Ref`'s w lane.
        assert!(n < 1 << 30, "BVH over {n} primitives: indices overflow");
        let (mut root, mut root_cb) = (Box4::EMPTY, Box4::EMPTY);
        for r in &refs {
            root.grow(&r.0);
            root_cb.grow_point(r.centroid2());
        }
        // A binary tree with at least one primitive per leaf: <= 2n - 1 nodes.
        let mut nodes: Vec<BvhNode> = Vec::with_capacity(2 * n - 1);
        nodes.push(root.bounds().to_node(0, 0));
        let root = Task { node: 0, first: 0, count: n, depth: 1, cb: root_cb };
        if n < par_min {
            grow(&mut nodes, &mut refs, 0, vec![root], false);
        } else {
            grow_parallel(&mut nodes, &mut refs, root);
        }
        nodes.shrink_to_fit();
        Bvh { nodes, prim_indices: collect_refs(n, par_min, |i| refs[i].prim()) }
    }
}

/// `(0..n).map(f).collect()`, on every core for at least `par_min` items.
fn collect_refs<T: Send>(n: usize, par_min: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let chunk = if n < par_min { n } else { PAR_BIN_CHUNK };
    crate::par::collect_each(n, chunk, f).unwrap_or_else(|e| panic!("BVH build: {e}"))
}

/// Splits `task` (its references are `refs[task.first - base ..]`) or makes it a leaf (None).
/// `par`: bin on every core.
fn step(
    nodes: &mut Vec<BvhNode>,
    refs: &mut [Ref],
    base: usize,
    task: Task,
    par: bool,
    scratch: &mut Scratch,
) -> Option<(Task, Task)> {
    let slice = &mut refs[task.first - base..task.first - base + task.count];
    let bounds = Bounds::of_node(&nodes[task.node]);
    let (m, lb, rb, lcb, rcb) = match decide(slice, &bounds, &task, par, scratch) {
        Decision::Leaf => {
            nodes[task.node].left_or_first = task.first as u32;
            nodes[task.node].count = task.count as u32;
            return None;
        }
        Decision::Sah { axis, bin, left, right } => {
            let binning = Binning::new(&task.cb, bin_count(task.count));
            let (i, lcb, rcb) = match axis {
                0 => binning.partition::<0>(slice, bin),
                1 => binning.partition::<1>(slice, bin),
                _ => binning.partition::<2>(slice, bin),
            };
            (i, left, right, lcb, rcb)
        }
        Decision::Median => {
            let e = task.cb.hi - task.cb.lo;
            let axis = if e.x >= e.y && e.x >= e.z {
                0
            } else if e.y >= e.z {
                1
            } else {
                2
            };
            let m = slice.len() / 2;
            slice.select_nth_unstable_by(m, |a, b| {
                a.centroid2()[axis].total_cmp(&b.centroid2()[axis]).then(a.prim().cmp(&b.prim()))
            });
            let (mut lb, mut rb, mut lcb, mut rcb) = (Box4::EMPTY, Box4::EMPTY, Box4::EMPTY, Box4::EMPTY);
            for (i, r) in slice.iter().enumerate() {
                let (b, cb) = if i < m { (&mut lb, &mut lcb) } else { (&mut rb, &mut rcb) };
                b.grow(&r.0);
                cb.grow_point(r.centroid2());
            }
            (m, lb, rb, lcb, rcb)
        }
    };
    debug_assert!(m > 0 && m < task.count);
    let left = nodes.len();
    nodes.push(lb.bounds().to_node(0, 0));
    nodes.push(rb.bounds().to_node(0, 0));
    nodes[task.node].left_or_first = left as u32;
    nodes[task.node].count = 0;
    let depth = task.depth + 1;
    Some((
        Task { node: left, first: task.first, count: m, depth, cb: lcb },
        Task { node: left + 1, first: task.first + m, count: task.count - m, depth, cb: rcb },
    ))
}

/// Builds the subtrees of `stack`'s tasks, depth first, left child first. `refs` holds the references
/// from index `base` of the whole build on.
fn grow(nodes: &mut Vec<BvhNode>, refs: &mut [Ref], base: usize, mut stack: Vec<Task>, par: bool) {
    let mut scratch = Scratch::new();
    while let Some(task) = stack.pop() {
        if let Some((left, right)) = step(nodes, refs, base, task, par, &mut scratch) {
            stack.push(right);
            stack.push(left);
        }
    }
}

/// Splits the largest task (binning on every core) until [`PAR_SUBTREES`] remain, then builds each
/// remaining subtree on a core and links its nodes in after the top's. Same SAH choices as `grow`;
/// only the node order differs.
fn grow_parallel(nodes: &mut Vec<BvhNode>, refs: &mut [Ref], root: Task) {
    let mut frontier = vec![root];
    let mut scratch = Scratch::new();
    while frontier.len() < PAR_SUBTREES {
        let Some((k, _)) = frontier
            .iter()
            .enumerate()
            .filter(|(_, t)| t.count > MAX_LEAF)
            .max_by_key(|(k, t)| (t.count, std::cmp::Reverse(*k)))
        else {
            break;
        };
        let task = frontier.remove(k);
        if let Some((left, right)) = step(nodes, refs, 0, task, true, &mut scratch) {
            frontier.insert(k, right);
            frontier.insert(k, left);
        }
    }
    // One disjoint reference range per subtree (the frontier is in reference order).
    let mut slices = Vec::with_capacity(frontier.len());
    let (mut rest, mut at) = (&mut refs[..], 0);
    for t in &frontier {
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(t.first - at);
        let (mine, tail) = tail.split_at_mut(t.count);
        slices.push(std::sync::Mutex::new(Some(mine)));
        (rest, at) = (tail, t.first + t.count);
    }
    let mut size_order: Vec<usize> = (0..frontier.len()).collect();
    size_order.sort_by_key(|&k| std::cmp::Reverse(frontier[k].count));
    let top = &nodes[..];
    let done = std::sync::atomic::AtomicUsize::new(0);
    let subtrees = crate::par::map(frontier.len(), &size_order, |k| {
        crate::progress::percent(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed), frontier.len());
        let t = &frontier[k];
        let slice =
            slices[k].lock().map(|mut s| s.take()).ok().flatten().expect("each subtree is built once");
        let mut sub = Vec::with_capacity(2 * t.count);
        sub.push(top[t.node]);
        let task = Task { node: 0, first: t.first, count: t.count, depth: t.depth, cb: t.cb };
        grow(&mut sub, slice, t.first, vec![task], false);
        sub
    })
    .unwrap_or_else(|e| panic!("BVH build: {e}"));
    // Subtree node i > 0 lands at base + i - 1; leaves already index the whole build's references.
    let mut bases = Vec::with_capacity(subtrees.len());
    let mut at = nodes.len() as u32;
    for sub in &subtrees {
        bases.push(at);
        at += sub.len() as u32 - 1;
    }
    let link = |k: usize, &n: &BvhNode| {
        let mut n = n;
        if n.count == 0 {
            n.left_or_first = bases[k] + n.left_or_first - 1;
        }
        n
    };
    for (k, (t, sub)) in frontier.iter().zip(&subtrees).enumerate() {
        nodes[t.node] = link(k, &sub[0]);
    }
    let parts: Vec<&[BvhNode]> = subtrees.iter().map(|s| &s[1..]).collect();
    crate::par::extend_parts(nodes, &parts, link).unwrap_or_else(|e| panic!("BVH build: {e}"));
}

/// Leaf, SAH split or median split for the node of `task` over `refs`; `par`: bin on every core.
fn decide(refs: &[Ref], bounds: &Bounds, task: &Task, par: bool, scratch: &mut Scratch) -> Decision {
    let count = refs.len();
    if count <= 1 {
        return Decision::Leaf;
    }
    // (half cost, axis, bin, left count)
    let mut best: Option<(f32, usize, usize, usize)> = None;
    let ext = (task.cb.hi - task.cb.lo).to_array();
    let nbins = bin_count(count);
    let binning = Binning::new(&task.cb, nbins);
    let Scratch { bins, right_cost } = scratch;
    if par && count >= 2 * PAR_BIN_CHUNK {
        let chunks: Vec<&[Ref]> = refs.chunks(PAR_BIN_CHUNK).collect();
        let parts = crate::par::map(chunks.len(), &[], |k| {
            let mut part = Scratch::new();
            bin_refs(chunks[k], &binning, &mut part.bins);
            part
        })
        .unwrap_or_else(|e| panic!("BVH build: {e}"));
        bins.iter_mut().for_each(|b| b[..nbins].fill(EMPTY_BIN));
        for part in parts {
            for (all, part) in bins.iter_mut().flatten().zip(part.bins.iter().flatten()) {
                all.count += part.count;
                all.bounds.grow(&part.bounds);
            }
        }
    } else {
        bin_refs(refs, &binning, bins);
    }
    // The sweeps are most of a small node's cost: half areas, no emptiness tests (a plane is only
    // costed with references on both sides), and only costs kept; the chosen plane's boxes are
    // gathered once afterwards. Halving is exact, so the choices are those of full areas.
    for (axis, bins) in bins.iter().enumerate() {
        // Axes without centroid extent are ignored; also skips NaN and infinite extents.
        if !(ext[axis] > 0.0 && ext[axis].is_finite()) {
            continue;
        }
        let (mut acc, mut n) = (Box4::EMPTY, 0u32);
        for i in (1..nbins).rev() {
            acc.grow(&bins[i].bounds);
            n += bins[i].count;
            right_cost[i] = acc.half_area_unchecked() * n as f32;
        }
        let (mut acc, mut n) = (Box4::EMPTY, 0usize);
        for i in 0..nbins - 1 {
            acc.grow(&bins[i].bounds);
            n += bins[i].count as usize;
            if n == 0 || n == count {
                continue;
            }
            let cost = acc.half_area_unchecked() * n as f32 + right_cost[i + 1];
            if best.as_ref().is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i, n));
            }
        }
    }
    let Some((half_cost, axis, bin, left_count)) = best else {
        // All centroids coincide: no plane separates them.
        return if count <= MAX_LEAF { Decision::Leaf } else { Decision::Median };
    };
    let cost = 2.0 * half_cost;
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
    let (mut left, mut right) = (Box4::EMPTY, Box4::EMPTY);
    for (i, b) in scratch.bins[axis][..nbins].iter().enumerate() {
        if i <= bin { &mut left } else { &mut right }.grow(&b.bounds);
    }
    Decision::Sah { axis, bin, left, right }
}

/// Counts and boxes of `refs` in their bins on each axis (the first `binning.last + 1` of `bins`), in
/// one pass (each box read once).
fn bin_refs(refs: &[Ref], binning: &Binning, bins: &mut [[Bin; BINS]; 3]) {
    let nbins = binning.last.x as usize + 1;
    bins.iter_mut().for_each(|b| b[..nbins].fill(EMPTY_BIN));
    let [xs, ys, zs] = bins;
    // Unrolled by hand, counts without overflow checks (below 2^30 references): at the crate's
    // opt-level the loop over three bins kept them on the stack and was a third of the binning.
    for r in refs {
        let [x, y, z] = binning.bins(r.centroid2());
        let (bx, by, bz) = (&mut xs[x], &mut ys[y], &mut zs[z]);
        bx.count = bx.count.wrapping_add(1);
        bx.bounds.grow(&r.0);
        by.count = by.count.wrapping_add(1);
        by.bounds.grow(&r.0);
        bz.count = bz.count.wrapping_add(1);
        bz.bounds.grow(&r.0);
    }
}
