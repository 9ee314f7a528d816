//! Unit tests of the split BVH: validity (coverage of every triangle's
//! clipped parts), agreement with the binned builder's closest hits, and the
//! quality report (SAH cost, node memory, build time) of binned vs full-sweep
//! vs SBVH on Sponza, the armadillo and the default scene.

use std::time::Instant;

use super::*;
use crate::accel::cpu_trace::{traverse_closest, triangle_positions};
use crate::scene::primitives::uv_sphere;

use super::test_rng::Rng;

/// Long thin triangles at random orientations plus small ones: the case
/// spatial splits exist for (boxes of long diagonal slivers overlap a lot).
fn slivers(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
    let mut r = Rng(seed);
    (0..n)
        .map(|i| {
            let c = r.v() * 100.0;
            if i % 3 == 0 {
                let d = (r.v() - 0.5) * 120.0;
                [c - d, c + d, c + d + (r.v() - 0.5) * 2.0]
            } else {
                [c + r.v() * 3.0, c + r.v() * 3.0, c + r.v() * 3.0]
            }
        })
        .collect()
}

fn aabbs(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
    tris.iter().map(|t| Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) }).collect()
}

#[test]
fn sbvh_covers_every_triangle() {
    for (n, seed) in [(1, 1), (2, 2), (5, 3), (100, 4), (3000, 5)] {
        let tris = slivers(n, seed);
        let (bvh, stats) = Bvh::build_sbvh_stats(&tris, Some(DEFAULT_ALPHA));
        bvh.validate_split(&tris).unwrap();
        if n >= 100 {
            assert!(stats.spatial_splits > 0, "{n} slivers: no spatial split");
            assert!(bvh.prim_indices.len() > n, "spatial splits duplicate references");
        }
        assert!(bvh.prim_indices.len() as f32 <= n as f32 * sbvh::MAX_DUPLICATION + 1.0);
        // Without spatial splits: every triangle exactly once, whole boxes.
        let sweep = Bvh::build_sbvh(&tris, None);
        sweep.validate(&aabbs(&tris)).unwrap();
    }
    let p = uv_sphere(1.0, 48, 24);
    let tris = triangle_positions(&p.vertices, &p.indices);
    Bvh::build_sbvh(&tris, Some(DEFAULT_ALPHA)).validate_split(&tris).unwrap();
    // Degenerate: identical and zero-area triangles.
    let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
    Bvh::build_sbvh(&vec![t; 50], Some(DEFAULT_ALPHA)).validate_split(&vec![t; 50]).unwrap();
    let line: Vec<[Vec3; 3]> =
        (0..200).map(|i| [Vec3::splat(i as f32), Vec3::splat(i as f32 + 5.0), Vec3::ZERO]).collect();
    Bvh::build_sbvh(&line, Some(DEFAULT_ALPHA)).validate_split(&line).unwrap();
    assert!(Bvh::build_sbvh(&[], Some(DEFAULT_ALPHA)).nodes.is_empty());
}

/// The parallel build (subtrees on every core, linked in) is as valid as
/// the serial one, at least as good by SAH cost, and the same tree every time.
#[test]
fn parallel_sbvh_is_valid_and_as_good_as_serial() {
    for (n, seed, alpha) in [(20_000, 7, Some(DEFAULT_ALPHA)), (5_000, 8, None), (40, 9, Some(DEFAULT_ALPHA))]
    {
        let tris = slivers(n, seed);
        let (serial, s) = Bvh::build_sbvh_in(&tris, alpha, usize::MAX);
        let (par, p) = Bvh::build_sbvh_in(&tris, alpha, 0);
        par.validate_split(&tris).unwrap();
        if alpha.is_none() {
            par.validate(&aabbs(&tris)).unwrap();
        }
        let (cs, cp) = (serial.sah_cost(), par.sah_cost());
        // Not worse; often better: the serial build spends the duplication
        // budget depth first, left subtrees first, the parallel one shares it
        // between its subtrees by size.
        assert!(cp <= 1.01 * cs, "{n} slivers: SAH cost serial {cs}, parallel {cp}");
        eprintln!("{n} slivers: SAH cost serial {cs:.1}, parallel {cp:.1}");
        assert_eq!(p.references, par.prim_indices.len());
        assert!(p.references as f32 <= n as f32 * sbvh::MAX_DUPLICATION + 1.0);
        assert!(s.spatial_splits == 0 || p.spatial_splits > 0);
        let again = Bvh::build_sbvh_in(&tris, alpha, 0).0;
        assert_eq!(bytemuck::cast_slice::<_, u8>(&again.nodes), bytemuck::cast_slice::<_, u8>(&par.nodes));
        assert_eq!(again.prim_indices, par.prim_indices);
    }
}

#[test]
fn sbvh_closest_hits_match_the_binned_bvh() {
    let tris = slivers(4000, 11);
    let binned = Bvh::build(&aabbs(&tris));
    let sbvh = Bvh::build_sbvh(&tris, Some(DEFAULT_ALPHA));
    let sweep = Bvh::build_sbvh(&tris, None);
    let mut r = Rng(12);
    let mut hits = 0;
    for _ in 0..4000 {
        let o = r.v() * 160.0 - 30.0;
        let d = r.v() * 100.0 - o;
        let a = traverse_closest(&binned, &tris, o, d, f32::INFINITY).map(|h| (h.0, h.1));
        let b = traverse_closest(&sbvh, &tris, o, d, f32::INFINITY).map(|h| (h.0, h.1));
        let c = traverse_closest(&sweep, &tris, o, d, f32::INFINITY).map(|h| (h.0, h.1));
        assert_eq!(a, b, "SBVH, ray {o} {d}");
        assert_eq!(a, c, "full sweep, ray {o} {d}");
        hits += a.is_some() as usize;
    }
    assert!(hits > 1000, "{hits} hits");
}

/// Per scene: triangle-weighted SAH cost, node memory and build time of the
/// binned builder, the full-sweep SAH builder and the SBVH over every
/// primitive's triangles (what the compute backend's static BLASes hold).
#[derive(Default)]
struct Quality {
    sah: f64,
    bytes: usize,
    nodes: usize,
    refs: usize,
    secs: f64,
    /// The same tree collapsed 4-wide with quantized bounds.
    wide_bytes: usize,
}

fn report(name: &str) -> [Quality; 3] {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("test asset {}: {e:#}", path.display()));
    let mut q: [Quality; 3] = Default::default();
    let mut tris_total = 0usize;
    for p in scene.meshes.iter().flat_map(|m| &m.primitives) {
        if p.indices.len() < 3 {
            continue;
        }
        let tris = triangle_positions(&p.vertices, &p.indices);
        tris_total += tris.len();
        for (k, q) in q.iter_mut().enumerate() {
            let t = Instant::now();
            let bvh = match k {
                0 => Bvh::build(&triangle_aabbs(&p.vertices, &p.indices)),
                1 => Bvh::build_sbvh(&tris, None),
                _ => Bvh::build_sbvh(&tris, Some(DEFAULT_ALPHA)),
            };
            q.secs += t.elapsed().as_secs_f64();
            if k == 2 {
                bvh.validate_split(&tris).unwrap();
            } else {
                bvh.validate(&aabbs(&tris)).unwrap();
            }
            q.sah += bvh.sah_cost() as f64 * tris.len() as f64;
            q.nodes += bvh.nodes.len();
            q.refs += bvh.prim_indices.len();
            q.bytes += bvh.nodes.len() * std::mem::size_of::<BvhNode>() + 4 * bvh.prim_indices.len();
            q.wide_bytes += WideBvh::from_binary(&bvh).bytes();
        }
    }
    for (label, q) in ["binned SAH", "full-sweep SAH", "SBVH (alpha 1e-5)"].iter().zip(&mut q) {
        q.sah /= tris_total as f64;
        eprintln!(
            "bvh quality {name}: {label}: {tris_total} tris, SAH cost {:.2}, {} nodes, {} refs ({:.3}x), {:.2} MiB ({:.2} MiB 4-wide), build {:.2} s",
            q.sah,
            q.nodes,
            q.refs,
            q.refs as f64 / tris_total as f64,
            q.bytes as f64 / (1 << 20) as f64,
            q.wide_bytes as f64 / (1 << 20) as f64,
            q.secs
        );
    }
    q
}

/// The quality report (issue 19 item 1). Asserted: full sweep within 2% of binning and SBVH within 0.5%
/// of the full sweep (all greedy; SBVH is 0.03% worse on the default scene's procedural meshes), and
/// SBVH strictly better on the two scanned/modelled scenes, whose long thin triangles need it.
/// The binned builder (skinned BLASes, top levels) is held within 1.2% of the full sweep (issue 35
/// item 11); measured binned / full-sweep SAH: Sponza 1.00371, armadillo 1.00792, default 1.00262.
#[test]
fn quality_report_binned_sweep_sbvh() {
    for scene in [
        "../shared/assets/scenes/SponzaCapsaicin/Sponza.gltf",
        "assets/armadillo_glass.toml",
        "assets/default.toml",
    ] {
        let [binned, sweep, sbvh] = report(scene);
        eprintln!("bvh quality {scene}: binned / full-sweep SAH {:.5}", binned.sah / sweep.sah);
        assert!(binned.sah <= sweep.sah * 1.012, "{scene}: binned {} vs sweep {}", binned.sah, sweep.sah);
        assert!(sweep.sah <= binned.sah * 1.02, "{scene}: sweep {} vs binned {}", sweep.sah, binned.sah);
        assert!(sbvh.sah <= sweep.sah * 1.005, "{scene}: SBVH {} vs sweep {}", sbvh.sah, sweep.sah);
        if !scene.ends_with("default.toml") {
            assert!(sbvh.sah < sweep.sah, "{scene}: SBVH {} vs sweep {}", sbvh.sah, sweep.sah);
        }
    }
}

/// Static trees: a split BVH up to SBVH_MAX_TRIANGLES, binned SAH above (where the split BVH's build
/// would dominate the load); both valid for the tracer.
#[test]
fn static_builder_by_size() {
    assert_eq!(StaticBuilder::for_triangles(SBVH_MAX_TRIANGLES), StaticBuilder::Sbvh);
    assert_eq!(StaticBuilder::for_triangles(SBVH_MAX_TRIANGLES + 1), StaticBuilder::Binned);
    let tris = slivers(3000, 31);
    let (bvh, builder) = Bvh::build_static(&tris);
    assert_eq!(builder, StaticBuilder::Sbvh);
    bvh.validate_split(&tris).unwrap();
    assert!(bvh.prim_indices.len() > tris.len(), "the split BVH's spatial splits duplicate references");
    let binned = Bvh::build_triangles(&tris);
    binned.validate(&aabbs(&tris)).unwrap();
    assert_eq!(binned.prim_indices.len(), tris.len());
    assert_eq!(
        bytemuck::cast_slice::<_, u8>(&binned.nodes),
        bytemuck::cast_slice::<_, u8>(&Bvh::build(&aabbs(&tris)).nodes)
    );
}
