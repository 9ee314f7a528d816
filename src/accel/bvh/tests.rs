//! Unit tests of the BVH: random, degenerate and skewed inputs, refit,
//! levels, the shader layout, build speed and quality, Sponza, and cube
//! lattices against their exact SAH optimum.

use std::time::Instant;

use super::build::levels_needed;
use super::*;
use crate::accel::cpu_trace::{traverse_closest, triangle_positions};
use crate::scene::primitives::uv_sphere;

use super::test_rng::Rng;

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

/// The parallel build (top splits binned on every core, then subtrees on the cores) makes the serial
/// build's tree: same primitive order, same leaves, same node count; only the node order differs.
#[test]
fn parallel_build_makes_the_serial_tree() {
    let leaves = |b: &Bvh| {
        let mut l: Vec<(u32, u32, [u32; 6])> = b
            .nodes
            .iter()
            .filter(|n| n.count > 0)
            .map(|n| {
                let c = [n.min, n.max].concat();
                (n.left_or_first, n.count, std::array::from_fn(|k| c[k].to_bits()))
            })
            .collect();
        l.sort_unstable();
        l
    };
    let mut inputs = vec![tri_aabbs(&soup(150_000, 21)), tri_aabbs(&noisy_grid(200, 50.0, 22))];
    inputs.extend([1, 2, 5, 33].map(|n| tri_aabbs(&soup(n, n as u64))));
    for a in inputs {
        let serial = Bvh::build_in(&a, usize::MAX);
        let par = Bvh::build_in(&a, 0);
        par.validate(&a).unwrap();
        assert_eq!(par.prim_indices, serial.prim_indices, "{} primitives", a.len());
        assert_eq!(par.nodes.len(), serial.nodes.len(), "{} primitives", a.len());
        assert_eq!(leaves(&par), leaves(&serial), "{} primitives", a.len());
        let (cs, cp) = (serial.sah_cost(), par.sah_cost());
        assert!((cs - cp).abs() <= 1e-5 * cs, "{} primitives: SAH cost serial {cs}, parallel {cp}", a.len());
        for (i, n) in par.nodes.iter().enumerate().filter(|(_, n)| n.count == 0) {
            assert!(n.left_or_first as usize > i, "children after parents");
        }
        let again = Bvh::build_in(&a, 0);
        assert_eq!(bytemuck::cast_slice::<_, u8>(&again.nodes), bytemuck::cast_slice::<_, u8>(&par.nodes));
    }
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
        "1M grid: {} tris in {:.3} s ({:.2} Mtri/s), {} nodes, SAH {:.4}, depth {}, refit {:.3} s",
        a.len(),
        s,
        a.len() as f64 / s / 1e6,
        bvh.nodes.len(),
        bvh.sah_cost(),
        bvh.depth(),
        refit_s
    );
    // Quality bounds (issue 35 item 11), measured: SAH 23.09, depth 21 against the 19 levels of a
    // balanced tree over 4-triangle leaves. (2 log2(n) = 40 would not bound anything: `validate`
    // already holds every tree to MAX_DEPTH = 32.)
    let balanced = levels_needed(a.len()) + 1;
    assert!(bvh.depth() <= balanced + 3, "1M grid: depth {} > {balanced} + 3", bvh.depth());
    assert!(bvh.sah_cost() <= 23.6, "1M grid: SAH {} > 23.6 (measured 23.09)", bvh.sah_cost());
    let p = uv_sphere(1.0, 1000, 500);
    let a = triangle_aabbs(&p.vertices, &p.indices);
    let t0 = Instant::now();
    let bvh = Bvh::build(&a);
    let s = t0.elapsed().as_secs_f64();
    bvh.validate(&a).unwrap();
    eprintln!(
        "1M sphere: {} tris in {:.3} s ({:.2} Mtri/s), SAH {:.4}, depth {}",
        a.len(),
        s,
        a.len() as f64 / s / 1e6,
        bvh.sah_cost(),
        bvh.depth()
    );
    // Measured: SAH 47.34, depth 24 (balanced: 19; the poles' slivers unbalance the SAH tree).
    let balanced = levels_needed(a.len()) + 1;
    assert!(bvh.depth() <= balanced + 6, "1M sphere: depth {} > {balanced} + 6", bvh.depth());
    assert!(bvh.sah_cost() <= 48.3, "1M sphere: SAH {} > 48.3 (measured 47.34)", bvh.sah_cost());
}

#[test]
fn sponza_builds_per_primitive_and_top_level() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/assets/scenes/SponzaCapsaicin/Sponza.gltf");
    // A missing asset is a failure, never a skip.
    assert!(
        std::path::Path::new(path).exists(),
        "test asset missing: {path} (CI keeps ../shared beside the checkout)"
    );
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

/// Unit cubes with their low corners at `xs` (ascending, at least 1 apart)
/// on x and `pitch` apart (>= 1) on y and z: `xs.len() x ny x nz` of them.
fn cube_lattice(xs: &[f32], ny: usize, nz: usize, pitch: f32) -> Vec<Aabb> {
    let mut a = Vec::with_capacity(xs.len() * ny * nz);
    for &x in xs {
        for j in 0..ny {
            for k in 0..nz {
                let min = Vec3::new(x, j as f32 * pitch, k as f32 * pitch);
                a.push(Aabb { min, max: min + Vec3::ONE });
            }
        }
    }
    a
}

/// The lowest SAH cost (as [`Bvh::sah_cost`] normalises it) of any tree over
/// `cube_lattice(xs, ny, nz, pitch)` whose every split is a lattice plane,
/// leaves of at most `MAX_LEAF` cubes. A sub-block's cost depends only on
/// its range of `xs` and its size on y and z, so this is an exact dynamic
/// programme over those: the leaf (when small enough) or the cheapest plane
/// on any axis, children optimal. The binned builder's SAH planes fall
/// between cubes' centroids, i.e. on lattice planes, so its tree is one of
/// these trees and can only match or exceed this.
fn optimal_lattice_sah(xs: &[f32], ny: usize, nz: usize, pitch: f32) -> f64 {
    let (nx, pitch) = (xs.len(), pitch as f64);
    let area = |i: usize, j: usize, b: usize, c: usize| {
        let x = (xs[j - 1] - xs[i]) as f64 + 1.0;
        let (y, z) = ((b - 1) as f64 * pitch + 1.0, (c - 1) as f64 * pitch + 1.0);
        2.0 * (x * y + y * z + z * x)
    };
    // Cost of the block over xs[i..j], b x c on y and z.
    let idx = |i: usize, j: usize, b: usize, c: usize| ((i * (nx + 1) + j) * (ny + 1) + b) * (nz + 1) + c;
    let mut cost = vec![f64::INFINITY; (nx + 1) * (nx + 1) * (ny + 1) * (nz + 1)];
    // Children are smaller on one axis and no larger on the others.
    for len in 1..=nx {
        for i in 0..=nx - len {
            let j = i + len;
            for b in 1..=ny {
                for c in 1..=nz {
                    let (ar, count) = (area(i, j, b, c), len * b * c);
                    let mut children = f64::INFINITY;
                    for s in i + 1..j {
                        children = children.min(cost[idx(i, s, b, c)] + cost[idx(s, j, b, c)]);
                    }
                    for s in 1..b {
                        children = children.min(cost[idx(i, j, s, c)] + cost[idx(i, j, b - s, c)]);
                    }
                    for s in 1..c {
                        children = children.min(cost[idx(i, j, b, s)] + cost[idx(i, j, b, c - s)]);
                    }
                    let mut best = TRAVERSAL_COST as f64 * ar + children;
                    if count <= MAX_LEAF {
                        best = best.min(INTERSECTION_COST as f64 * count as f64 * ar);
                    }
                    cost[idx(i, j, b, c)] = best;
                }
            }
        }
    }
    cost[idx(0, nx, ny, nz)] / area(0, nx, ny, nz)
}

/// Absolute quality (issue 35 item 11): on lattices of cubes the optimum over lattice-plane trees is
/// known exactly (above), so the binned builder is held to it, not only to another builder. Measured
/// ratios to the optimum, and the bounds set a little above them:
///
/// * uniform 32^3 and 64 x 128 x 1: 1 (to f32 rounding): their halving planes are bin boundaries and
///   greedy SAH finds the optimum. Bound 1.0001.
/// * uniform 37 x 23 x 11 (pitch 1 and 1.5), 3 x 100 x 70 (pitch 2): 1.0178, 1.0133, 1.0098 (the
///   greedy tree, not the bins, loses: 2 or 4 bins give the same ratios). Bound 1.025.
/// * gaps growing along x, 64 x 8 x 8 and 48 x 8 x 8: 1.0044 and 1.0047. Bound 1.01; SAH over the
///   longest axis only gives 1.017 and 1.029.
/// * gaps growing along x, 64 x 16 x 2 at pitch 3: 1.0221. Bound 1.03.
#[test]
fn binned_sah_is_near_optimal_on_cube_lattices() {
    let uniform = |n: usize, pitch: f32| (0..n).map(|i| i as f32 * pitch).collect::<Vec<_>>();
    // Gaps growing along x, so the best planes are neither the median nor the middle.
    let quadratic: Vec<f32> = (0..64).map(|i| (i as f32 + 0.02 * (i * i) as f32).round()).collect();
    let exponential: Vec<f32> = (0..48).map(|i| 1.07f32.powi(i).round() + 2.0 * i as f32).collect();
    for (xs, ny, nz, pitch, bound) in [
        (uniform(32, 1.0), 32, 32, 1.0, 1.0001),
        (uniform(64, 1.0), 128, 1, 1.0, 1.0001),
        (uniform(37, 1.0), 23, 11, 1.0, 1.025),
        (uniform(37, 1.5), 23, 11, 1.5, 1.025),
        (uniform(3, 2.0), 100, 70, 2.0, 1.025),
        (quadratic.clone(), 8, 8, 1.0, 1.01),
        (exponential, 8, 8, 1.0, 1.01),
        (quadratic, 16, 2, 3.0, 1.03),
    ] {
        let a = cube_lattice(&xs, ny, nz, pitch);
        let bvh = check(&a);
        let (got, best) = (bvh.sah_cost() as f64, optimal_lattice_sah(&xs, ny, nz, pitch));
        let dims = [xs.len(), ny, nz];
        eprintln!(
            "lattice {dims:?} pitch {pitch}: binned SAH {got:.4}, optimum {best:.4}, ratio {:.5}, depth {}",
            got / best,
            bvh.depth()
        );
        assert!(got >= best * (1.0 - 1e-5), "lattice {dims:?}: binned {got} below the optimum {best}?");
        assert!(
            got <= best * bound,
            "lattice {dims:?} pitch {pitch}: binned SAH {got} > {bound} x the optimum {best}"
        );
    }
}
