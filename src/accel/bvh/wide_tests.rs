//! Unit tests of the 4-wide quantized BVH: conservative decode, and a CPU
//! reference traversal (near-to-far over sorted hit children, short stack)
//! that finds the binary tree's closest hits.

use super::*;
use crate::accel::cpu_trace::{ray_aabb, traverse_closest, triangle_positions, WatertightRay};
use crate::scene::primitives::uv_sphere;

use super::test_rng::Rng;

fn soup(n: usize, seed: u64, offset: Vec3) -> Vec<[Vec3; 3]> {
    let mut r = Rng(seed);
    (0..n)
        .map(|i| {
            let c = offset + r.v() * 100.0;
            let s = if i % 5 == 0 { 30.0 } else { 3.0 };
            [c + r.v() * s, c + r.v() * s, c + r.v() * s]
        })
        .collect()
}

fn aabbs(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
    tris.iter().map(|t| Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) }).collect()
}

/// Every decoded child box contains the exact box it was made from; the
/// tree covers every wide node once and every leaf range of the source.
fn check_conservative(bvh: &Bvh, w: &WideBvh) {
    let mut leaves = 0;
    let mut seen = vec![false; w.nodes.len()];
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        assert!(!std::mem::replace(&mut seen[i], true), "wide node {i} reached twice");
        let n = &w.nodes[i];
        assert!((1..=wide::WIDTH).contains(&n.children()) && (i > 0 || n.children() >= 1));
        for c in 0..n.children() {
            let d = n.child_bounds(c);
            let src = &bvh.nodes[w.source[i][c] as usize];
            for k in 0..3 {
                assert!(
                    d.min[k] <= src.min[k] && d.max[k] >= src.max[k],
                    "node {i} child {c} axis {k}: decoded {:?} does not contain exact {:?}..{:?}",
                    d,
                    src.min,
                    src.max
                );
            }
            match n.leaf(c) {
                Some((first, count)) => {
                    assert_eq!((first, count), (src.left_or_first as usize, src.count as usize));
                    leaves += 1;
                }
                None => {
                    assert!(n.child[c] as usize > i && src.count == 0);
                    stack.push(n.child[c] as usize);
                }
            }
        }
    }
    assert!(seen.iter().all(|&s| s), "unreachable wide nodes");
    assert_eq!(leaves, bvh.nodes.iter().filter(|n| n.count > 0).count());
}

/// Closest hit through the wide tree: hit children sorted by entry distance,
/// the nearest visited next, the rest pushed far-first. Returns the hit and
/// the number of wide nodes visited.
fn wide_closest(w: &WideBvh, tris: &[[Vec3; 3]], o: Vec3, d: Vec3) -> (Option<(u32, f32)>, usize) {
    let ray = WatertightRay::new(o, d);
    let inv = d.recip();
    let mut tmax = f32::INFINITY;
    let mut best = None;
    let mut visits = 0;
    if w.nodes.is_empty() {
        return (None, 0);
    }
    // (child reference: node index or leaf child word, entry t)
    let mut stack: Vec<(u32, f32)> = vec![(0, 0.0)];
    while let Some((c, t)) = stack.pop() {
        if t > tmax {
            continue;
        }
        if c & wide::LEAF_BIT != 0 {
            let (first, count) = ((c & 0x07FF_FFFF) as usize, ((c >> 27) & 7) as usize);
            for &p in &w.prim_indices[first..first + count] {
                let t = &tris[p as usize];
                if let Some((th, _, _)) = ray.intersect(t[0], t[1], t[2], tmax) {
                    tmax = th;
                    best = Some((p, th));
                }
            }
            continue;
        }
        visits += 1;
        let n = &w.nodes[c as usize];
        let mut hits: Vec<(u32, f32)> = (0..n.children())
            .filter_map(|i| ray_aabb(o, inv, 0.0, tmax, &n.child_bounds(i)).map(|t| (n.child[i], t)))
            .collect();
        hits.sort_by(|a, b| b.1.total_cmp(&a.1)); // far first: the nearest is popped next
        stack.extend(hits);
    }
    (best, visits)
}

fn agree(tris: &[[Vec3; 3]], bvh: &Bvh, seed: u64) -> (usize, usize) {
    let w = WideBvh::from_binary(bvh);
    check_conservative(bvh, &w);
    let (lo, hi) = aabbs(tris)
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), b| (l.min(b.min), h.max(b.max)));
    let mut r = Rng(seed);
    let (mut hits, mut visits) = (0, 0);
    for _ in 0..3000 {
        let o = lo + (r.v() * 1.6 - 0.3) * (hi - lo);
        let d = lo + r.v() * (hi - lo) - o;
        let a = traverse_closest(bvh, tris, o, d, f32::INFINITY).map(|h| (h.0, h.1));
        let (b, v) = wide_closest(&w, tris, o, d);
        assert_eq!(a, b, "ray {o} {d}");
        hits += a.is_some() as usize;
        visits += v;
    }
    (hits, visits)
}

#[test]
fn wide_node_layout_is_one_cache_line() {
    assert_eq!(std::mem::size_of::<WideNode>(), 64);
    assert_eq!(std::mem::offset_of!(WideNode, meta), 12);
    assert_eq!(std::mem::offset_of!(WideNode, qmin), 16);
    assert_eq!(std::mem::offset_of!(WideNode, qmax), 28);
    assert_eq!(std::mem::offset_of!(WideNode, child), 40);
}

#[test]
fn wide_decode_is_conservative_and_closest_hits_match() {
    // Far from the origin too: large coordinates, small boxes (rounding).
    for (i, offset) in [Vec3::ZERO, Vec3::new(1e5, -3e4, 7e5)].into_iter().enumerate() {
        let tris = soup(5000, 21 + i as u64, offset);
        for bvh in [Bvh::build(&aabbs(&tris)), Bvh::build_sbvh(&tris, Some(DEFAULT_ALPHA))] {
            let (hits, _) = agree(&tris, &bvh, 5 + i as u64);
            assert!(hits > 1000, "{hits} hits");
        }
    }
    let p = uv_sphere(1.0, 64, 32);
    let tris = triangle_positions(&p.vertices, &p.indices);
    let bvh = Bvh::build_sbvh(&tris, Some(DEFAULT_ALPHA));
    let (hits, visits) = agree(&tris, &bvh, 9);
    let w = WideBvh::from_binary(&bvh);
    eprintln!(
        "sphere: binary {} nodes ({} B), wide {} nodes ({} B), {:.1} wide nodes per ray, {hits} hits",
        bvh.nodes.len(),
        bvh.nodes.len() * 32 + 4 * bvh.prim_indices.len(),
        w.nodes.len(),
        w.bytes(),
        visits as f64 / 3000.0
    );
    // Tiny inputs: a single leaf root, two triangles, flat (zero-extent) axes.
    for tris in [soup(1, 3, Vec3::ZERO), soup(2, 4, Vec3::ZERO), vec![[Vec3::ZERO, Vec3::X, Vec3::Y]; 9]] {
        let bvh = Bvh::build_sbvh(&tris, Some(DEFAULT_ALPHA));
        agree(&tris, &bvh, 1);
    }
    assert!(WideBvh::from_binary(&Bvh::default()).nodes.is_empty());
}

/// The parallel collapse (top breadth first, subtrees on the cores) gives the serial collapse's tree:
/// the same nodes in a depth-first walk, with their sources; only the node order differs.
#[test]
fn parallel_collapse_makes_the_serial_tree() {
    let canonical = |w: &WideBvh| {
        let (mut out, mut stack) = (Vec::new(), vec![0usize]);
        while let Some(i) = stack.pop() {
            let mut n = w.nodes[i];
            for c in 0..n.children() {
                if n.child[c] & super::wide::LEAF_BIT == 0 {
                    stack.push(n.child[c] as usize);
                    n.child[c] = 0;
                }
            }
            out.push((n, w.source[i]));
        }
        out
    };
    let tris = soup(30_000, 41, Vec3::ZERO);
    for bvh in [Bvh::build(&aabbs(&tris)), Bvh::build_sbvh(&tris, Some(DEFAULT_ALPHA))] {
        let serial = WideBvh::from_binary_in(&bvh, usize::MAX);
        let par = WideBvh::from_binary_in(&bvh, 0);
        assert_eq!(par.nodes.len(), serial.nodes.len());
        assert_eq!(canonical(&par), canonical(&serial));
        assert_eq!(par.prim_indices, serial.prim_indices);
        check_conservative(&bvh, &par);
    }
    // Trees smaller than the top's frontier collapse all in the top.
    let small = Bvh::build(&aabbs(&soup(20, 42, Vec3::ZERO)));
    assert_eq!(
        canonical(&WideBvh::from_binary_in(&small, 0)),
        canonical(&WideBvh::from_binary_in(&small, usize::MAX))
    );
}

/// The exponent from the bits is ceil(log2 x) (in f64: f32's log2 rounds 2^e * (1 + ulp) down to e),
/// powers of two and subnormals included.
#[test]
fn ceil_log2_from_bits_matches_libm() {
    let mut r = Rng(77);
    let mut xs: Vec<f32> =
        (-126..=127).map(super::wide::exp2i).flat_map(|p| [p, p * 1.0000001, p * 0.99999994]).collect();
    xs.extend((0..10_000).map(|_| r.v().x * 10f32.powi((r.v().y * 60.0) as i32 - 30)).filter(|x| *x > 0.0));
    for x in xs.into_iter().filter(|x| x.is_normal()) {
        assert_eq!(super::wide::ceil_log2(x), ((x as f64).log2().ceil() as i32).max(-126), "x = {x:e}");
    }
    assert_eq!(super::wide::ceil_log2(f32::from_bits(1)), -126, "subnormal");
}

/// Quantization is tight: a node's exponent is the smallest that holds its children, so on nearly
/// every axis with extent the largest child bound uses more than half of the 8-bit range (one
/// exponent too many would put every one at or below 128).
#[test]
fn quantization_uses_the_smallest_exponent() {
    let tris = soup(20_000, 43, Vec3::new(3e3, -70.0, 0.5));
    let w = WideBvh::from_binary(&Bvh::build(&aabbs(&tris)));
    let (mut axes, mut tight) = (0, 0);
    for n in &w.nodes {
        for k in 0..3 {
            let top = (0..n.children()).map(|i| (n.qmax[k] >> (8 * i)) & 0xFF).max().unwrap_or(0);
            let bottom = (0..n.children()).map(|i| (n.qmin[k] >> (8 * i)) & 0xFF).min().unwrap_or(0);
            if top > bottom {
                axes += 1;
                tight += (top > 128) as usize;
            }
        }
    }
    assert!(tight * 100 >= axes * 95, "{tight} of {axes} node axes use more than half the range");
}
