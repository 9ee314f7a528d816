//! `bench --builders`: the static-geometry BVH builders side by side on generated scenes (issue 36):
//! the host's binned SAH (what the compute BVH uses above SBVH_MAX_TRIANGLES) and split BVH (below),
//! the LBVH on the host (one thread) and the LBVH on the device (accel/lbvh.rs; GPU ms per step from
//! timestamps). Each builds a binary tree over the same world-space triangles; the table gives build
//! ms, Mtri/s and the tree's SAH cost (lower traces faster).

use std::time::Instant;

use anyhow::Result;

use super::scale::Point;
use crate::accel::bvh::{Bvh, SBVH_MAX_TRIANGLES};
use crate::accel::flat::static_triangles;
use crate::accel::lbvh;
use crate::app::{with_context, GpuOptions};
use crate::gpu::origin::RenderOrigin;

/// One builder's figures on one scene.
struct Row {
    builder: String,
    ms: f64,
    sah: f32,
    detail: String,
}

pub fn builders_command(gpu: &GpuOptions, points: &[Point]) -> Result<()> {
    with_context(gpu, |ctx| {
        println!("| scene | triangles | builder | build ms | Mtri/s | SAH cost | detail |");
        println!("|---|---:|---|---:|---:|---:|---|");
        for &point in points {
            let scene = point.scene()?;
            let tris = static_triangles(&scene, RenderOrigin::for_scene(&scene));
            let n = tris.len();
            let timed = |f: &dyn Fn() -> Bvh| {
                let t = Instant::now();
                let bvh = f();
                (t.elapsed().as_secs_f64() * 1e3, bvh.sah_cost())
            };
            let mut rows = Vec::new();
            let (ms, sah) = timed(&|| Bvh::build_triangles(&tris));
            rows.push(Row {
                builder: "binned SAH (host, every core)".into(),
                ms,
                sah,
                detail: String::new(),
            });
            if n <= SBVH_MAX_TRIANGLES {
                let (ms, sah) = timed(&|| Bvh::build_sbvh(&tris, Some(crate::accel::bvh::DEFAULT_ALPHA)));
                rows.push(Row {
                    builder: "split BVH (host, every core)".into(),
                    ms,
                    sah,
                    detail: String::new(),
                });
            }
            let (ms, sah) = timed(&|| lbvh::reference_bvh(&tris).expect("the host LBVH is a tree"));
            rows.push(Row { builder: "LBVH (host, one thread)".into(), ms, sah, detail: String::new() });
            // Once to compile and warm, then measured.
            lbvh::build_on_device(ctx, &tris)?;
            let dev = lbvh::build_on_device(ctx, &tris)?;
            let gpu_ms: f64 = dev.pass_ms.iter().map(|(_, ms)| ms).sum();
            let steps: Vec<String> = dev
                .pass_ms
                .iter()
                .map(|(name, ms)| format!("{} {ms:.1}", name.trim_start_matches("lbvh ")))
                .collect();
            rows.push(Row {
                builder: "LBVH (device)".into(),
                ms: gpu_ms + dev.host_ms,
                sah: dev.bvh.sah_cost(),
                detail: format!("GPU ms: {}; host centroid bounds {:.1} ms", steps.join(", "), dev.host_ms),
            });
            for r in rows {
                println!(
                    "| {point} | {n} | {} | {:.1} | {:.2} | {:.1} | {} |",
                    r.builder,
                    r.ms,
                    n as f64 / (r.ms.max(1e-3) * 1e3),
                    r.sah,
                    r.detail
                );
            }
        }
        Ok(())
    })
}
