//! `bench`: per-pass GPU times along the scene's camera path, variants
//! measured side by side, and the refit-quality check of animated runs.

use std::path::Path;

use anyhow::{bail, Context as _, Result};

use super::bench_tables::{bench_csv, paired_ratios, ratio_word, stats, BenchReport, BudgetFrame};
use super::{
    check_validation, load_posed, log_frame_health, resolve_shading, with_context, GpuOptions, RenderJob,
};
use crate::accel::dynamic::RebuildPolicy;
use crate::render::settings::PrimaryVisibility;
use crate::render::shading::{Backend, Effects, Mode};
use crate::render::{RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
use crate::vk::Context;

/// How a benchmark keeps the acceleration structures current when the
/// scene animates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum AccelUpdate {
    /// Refit skinned structures, rebuilding by the default policy.
    #[default]
    Policy,
    /// Refit skinned structures every frame, never rebuild.
    Refit,
    /// Rebuild skinned structures every frame (BUILD instead of UPDATE).
    Rebuild,
    /// Rebuild every acceleration structure from scratch every frame.
    Full,
}

impl AccelUpdate {
    /// The refit / rebuild policy of the dynamic structures.
    pub fn rebuild_policy(self) -> RebuildPolicy {
        match self {
            AccelUpdate::Policy => RebuildPolicy::default(),
            AccelUpdate::Refit => RebuildPolicy::NEVER,
            AccelUpdate::Rebuild | AccelUpdate::Full => RebuildPolicy::ALWAYS,
        }
    }

    /// Brings `renderer`'s acceleration structures to `scene`'s current
    /// pose this way (its `update.timings` say what it cost).
    pub fn update(self, ctx: &Context, renderer: &mut Renderer, scene: &Scene) -> Result<()> {
        renderer.update.policy = self.rebuild_policy();
        if self == AccelUpdate::Full {
            renderer.rebuild_all_structures(ctx, scene)
        } else {
            renderer.update_scene(ctx, scene)
        }
    }
}

/// One measured configuration of a benchmark run.
#[derive(Clone, Copy, Debug)]
pub struct BenchVariant {
    pub mode: Mode,
    pub backend: Backend,
    pub accel: AccelUpdate,
}

/// What one benchmark frame gave: the scene update's and the frame's pass
/// times, and the update's refit / rebuild counts.
struct BenchFrame {
    update: Vec<(&'static str, f64)>,
    timings: Vec<(&'static str, f64)>,
    counts: [usize; 2],
    bad_pixels: u32,
    exposure: Option<crate::render::tone::ExposureState>,
    /// Effects mode: the ray stages' predicted and measured ms and rays.
    budget: Option<BudgetFrame>,
}

/// Renders frame `i` of a benchmark of `variant` (warm-up frames first:
/// the camera stays at the path's start until `warmup`).
#[allow(clippy::too_many_arguments)]
fn bench_frame(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &mut Scene,
    anim: Option<usize>,
    job: &RenderJob,
    base_camera: &Camera,
    variant: BenchVariant,
    i: usize,
    (warmup, frames): (usize, usize),
    frame_no: &mut u64,
) -> Result<BenchFrame> {
    let what = format!(
        "bench frame {frame_no} ({:?} mode, {:?} backend, {} frame {i})",
        variant.mode,
        variant.backend,
        if i < warmup { "warm-up" } else { "path" }
    );
    *frame_no += 1;
    ctx.capture_frame_if(*frame_no - 1, &what, || {
        bench_frame_inner(ctx, renderer, scene, anim, job, base_camera, variant, i, (warmup, frames))
    })
}

#[allow(clippy::too_many_arguments)]
fn bench_frame_inner(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &mut Scene,
    anim: Option<usize>,
    job: &RenderJob,
    base_camera: &Camera,
    variant: BenchVariant,
    i: usize,
    (warmup, frames): (usize, usize),
) -> Result<BenchFrame> {
    let settings = RenderSettings { mode: variant.mode, backend: variant.backend, ..job.settings };
    renderer.update.policy = variant.accel.rebuild_policy();
    let t = if frames > 1 { (i.saturating_sub(warmup)) as f32 / (frames - 1) as f32 } else { 0.0 };
    let camera = crate::scene::camera::on_path(&scene.camera_path, t, base_camera);
    let mut update = Vec::new();
    let mut counts = [0; 2];
    if let Some(a) = anim {
        // Fixed-step clock: deterministic frames.
        scene.animate(a, job.time + i as f32 / job.fps.max(1e-3));
        variant.accel.update(ctx, renderer, scene)?;
        update = renderer.update.timings.clone();
        counts = renderer.update.counts;
    }
    // The prediction the selection this frame honours was made with.
    let predicted = renderer
        .budget_report()
        .filter(|r| Some(r.settings) == settings.budget)
        .and_then(|r| Some((r.predicted_ms?, r.predicted_rays?.iter().sum::<f64>())));
    let out = renderer.render(ctx, scene, &camera, &settings)?;
    if i == warmup {
        log_frame_health(&out);
    }
    let ray_ms = out.budgeted_ms();
    Ok(BenchFrame {
        update,
        timings: out.timings,
        counts,
        bad_pixels: out.bad_pixels,
        exposure: out.exposure,
        budget: predicted.map(|(predicted_ms, predicted_rays)| BudgetFrame {
            predicted_ms,
            measured_ms: ray_ms,
            predicted_rays,
            measured_rays: renderer.budget_report().map_or(f64::NAN, |r| r.measured_rays.iter().sum()),
        }),
    })
}

/// `bench`: each variant gets its own renderer and a warm-up (one ray-counting frame, then `warmup`
/// unmeasured frames at the path's start, so no variant absorbs the process's warm-up). The variants
/// are then measured interleaved, frame by frame along the camera path (or from its camera) with the
/// order rotating: a drift in the device's speed (a CPU's clock, other load) falls on every variant
/// alike, and frames pair up for per-frame ratios (`paired_ratios`). Progress goes to stderr.
pub fn bench(
    ctx: &Context,
    job: &RenderJob,
    frames: usize,
    warmup: usize,
    variants: &[BenchVariant],
) -> Result<Vec<BenchReport>> {
    let extent = job.extent()?;
    let mut load = Some(crate::progress::begin());
    let (mut scene, anim) = load_posed(job)?;
    let base_camera = job.camera.resolve(&scene)?;
    // An explicit --look-from/--look-at holds the camera there: the scene's path is for the default run.
    if matches!(job.camera, crate::app::CameraChoice::LookAt { .. }) && !scene.camera_path.is_empty() {
        log::info!("bench: --look-from holds the camera; the scene's camera path is not followed");
        scene.camera_path.clear();
    }
    // Every variant asked for must run: a skipped one would read as measured.
    let unavailable: Vec<String> = variants
        .iter()
        .filter_map(|v| {
            let settings = RenderSettings { mode: v.mode, backend: v.backend, ..job.settings };
            resolve_shading(ctx, &scene, &settings).err().map(|e| format!("{:?} mode: {e:#}", v.mode))
        })
        .collect();
    if !unavailable.is_empty() {
        bail!("bench: not every variant asked for can run on {}: {}", ctx.caps.name, unavailable.join("; "));
    }
    let n = variants.len();
    // Warm-up frames per variant: under auto primary visibility at least until both techniques have run
    // (each pass's first frame compiles its shaders on a software device; a probe reaching the traced
    // pass within the measured frames cost one of them seconds). The extra frames repeat the path's
    // first, so the measured frames are the same whatever the count.
    let warm: Vec<usize> = variants
        .iter()
        .map(|v| {
            let auto = v.mode == Mode::Hybrid && job.settings.primary_visibility == PrimaryVisibility::Auto;
            if auto {
                warmup.max(crate::render::visibility::FRAMES_TO_WARM_BOTH as usize)
            } else {
                warmup
            }
        })
        .collect();
    // Frames in rendering order: per variant a ray-counting frame and the warm-up, then one measured
    // frame per variant for each frame of the path; `--capture-frame` counts the same way.
    let total = warm.iter().map(|w| 1 + w + frames).sum::<usize>();
    if let Some(c) = ctx.capture_frame.filter(|&c| c >= total as u64) {
        bail!("--capture-frame {c}: this bench renders {total} frames (0..={})", total - 1);
    }
    let mut renderers: Vec<Renderer> = Vec::new();
    let mut reports = Vec::new();
    let mut frame_no = 0u64;
    let result: Result<()> = (|| {
        let mut rays = Vec::new();
        for (k, &v) in variants.iter().enumerate() {
            eprintln!(
                "bench: warming up {}/{n} ({} frames): {:?} mode, {:?} backend, AS update {:?}",
                k + 1,
                warm[k],
                v.mode,
                v.backend,
                v.accel
            );
            renderers.push(Renderer::new(ctx, &scene, extent)?);
            let renderer = renderers.last_mut().context("just pushed")?;
            // Auto primary visibility measures like the viewer's does.
            renderer.choices.visibility.measure = true;
            // The camera path adapts like a played-back animation: 1 / fps
            // per frame (the first frame converges at once).
            renderer.choices.adapt_dt = Some(1.0 / job.fps.max(1e-3));
            // One counted frame: the atomics would distort the timings.
            let settings = RenderSettings { mode: v.mode, backend: v.backend, ..job.settings };
            let counting =
                RenderSettings { effects: Effects { count_rays: true, ..settings.effects }, ..settings };
            let what =
                format!("bench frame {frame_no} ({:?} mode, {:?} backend, ray counts)", v.mode, v.backend);
            frame_no += 1;
            let counted = ctx.capture_frame_if(frame_no - 1, &what, || {
                renderer.render(ctx, &scene, &base_camera, &counting)
            })?;
            rays.push(counted.ray_counts);
            load.take();
            for w in 0..warm[k] {
                let i = (w + warmup).saturating_sub(warm[k]);
                bench_frame(
                    ctx,
                    renderer,
                    &mut scene,
                    anim,
                    job,
                    &base_camera,
                    v,
                    i,
                    (warmup, frames),
                    &mut frame_no,
                )?;
            }
        }
        if n > 1 {
            eprintln!("bench: measuring {n} variants interleaved, {frames} frames each");
        } else {
            eprintln!("bench: measuring {frames} frames");
        }
        let mut acc: Vec<Measured> = (0..n).map(|_| Measured::default()).collect();
        let step = (frames / 10).max(1);
        for (j, i) in (warmup..warmup + frames).enumerate() {
            if j % step == 0 && frames >= 20 {
                eprintln!("bench: frame {}/{frames}", j + 1);
            }
            for r in 0..n {
                // The order rotates: no variant always follows the same one.
                let k = (r + j) % n;
                let f = bench_frame(
                    ctx,
                    &mut renderers[k],
                    &mut scene,
                    anim,
                    job,
                    &base_camera,
                    variants[k],
                    i,
                    (warmup, frames),
                    &mut frame_no,
                )?;
                acc[k].add(f);
            }
        }
        for (k, (m, renderer)) in acc.into_iter().zip(&renderers).enumerate() {
            let v = variants[k];
            let c = renderer.shading_config().map(|c| c.describe()).unwrap_or_default();
            let config = match anim {
                Some(_) if v.accel == AccelUpdate::Full => {
                    format!("{c}; AS update: Full (every structure rebuilt every frame)")
                }
                Some(_) => format!(
                    "{c}; AS update: {:?} ({} refits, {} rebuilds of skinned structures)",
                    v.accel, m.counts[0], m.counts[1]
                ),
                None => c,
            };
            reports.push(BenchReport {
                scene: job.scene.clone(),
                device: ctx.caps.name.clone(),
                config,
                variant: v,
                width: job.width,
                height: job.height,
                frames,
                passes: m.per_pass.into_iter().map(|(n, v)| stats(n, v)).collect(),
                frame_total: stats("frame", m.totals.clone()),
                frame_totals: m.totals,
                rays_first_frame: rays[k],
                bad_pixels: m.bad_pixels,
                exposure: m.exposure,
                budget: job
                    .settings
                    .budget
                    .filter(|b| {
                        b.mode == crate::render::budget::BudgetMode::Effects && !m.budget_frames.is_empty()
                    })
                    .map(|b| (b.budget, m.budget_frames)),
                gbuffer_bytes_per_pixel: crate::render::passes::gbuffer::bytes_per_pixel(renderer.targets()),
                raster_draws: renderer.raster_draws(),
                raster_triangles: renderer.raster_triangles(),
                occlusion: renderer
                    .occlusion_counts()
                    .map(|c| (c, renderer.gpu.clusters.list.clusters.len())),
                visibility: renderer.choices.visibility.describe(),
            });
        }
        Ok(())
    })();
    for mut r in renderers {
        r.destroy(ctx);
    }
    result?;
    Ok(reports)
}

/// One variant's measured frames, accumulated.
#[derive(Default)]
struct Measured {
    per_pass: Vec<(&'static str, Vec<f64>)>,
    /// GPU ms per frame, in path order.
    totals: Vec<f64>,
    counts: [usize; 2],
    bad_pixels: u64,
    exposure: Option<crate::render::tone::ExposureState>,
    budget_frames: Vec<BudgetFrame>,
}

impl Measured {
    fn add(&mut self, f: BenchFrame) {
        self.counts = [self.counts[0] + f.counts[0], self.counts[1] + f.counts[1]];
        self.bad_pixels += f.bad_pixels as u64;
        self.exposure = f.exposure;
        self.budget_frames.extend(f.budget);
        let mut total = 0.0;
        for &(name, ms) in f.update.iter().chain(&f.timings).filter(|(n, _)| *n != "readback") {
            total += ms;
            match self.per_pass.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => v.push(ms),
                None => self.per_pass.push((name, vec![ms])),
            }
        }
        self.totals.push(total);
    }
}

pub fn bench_command(
    gpu: &GpuOptions,
    job: &RenderJob,
    frames: usize,
    warmup: usize,
    variants: &[BenchVariant],
    csv: Option<&Path>,
) -> Result<()> {
    with_context(gpu, |ctx| bench_with(ctx, job, frames, warmup, variants, csv))
}

fn bench_with(
    ctx: &Context,
    job: &RenderJob,
    frames: usize,
    warmup: usize,
    variants: &[BenchVariant],
    csv: Option<&Path>,
) -> Result<()> {
    let reports = bench(ctx, job, frames.max(1), warmup, variants)?;
    for r in &reports {
        println!("{}", r.table());
    }
    if let Some(q) = refit_quality(job, frames.max(1) + warmup)? {
        println!(
            "refit quality over these frames (CPU trees, built at the first frame, refit after): \
             SAH cost of the refit trees / fresh builds: worst {:.3}, last {:.3}; \
             bounds area growth worst {:.2}x (the default policy rebuilds past 1.5x).\n\
             CPU alternative to GPU skinning + BVH refit (not used): {:.3} ms per frame \
             (skin + triangle boxes + refit on the host; the node upload would come on top)\n",
            q.worst_sah_ratio, q.last_sah_ratio, q.worst_area_growth, q.cpu_refit_ms
        );
    }
    if reports.len() > 1 {
        println!("{}", side_by_side(&reports));
    }
    if let Some(path) = csv {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        std::fs::write(path, bench_csv(&reports)).with_context(|| format!("writing {}", path.display()))?;
        log::info!("wrote {}", path.display());
    }
    check_validation(ctx)
}

/// The variants against the first: one ratio each, the median of the per-frame ratios (frames rendered
/// next to each other at the same path position, so a drift in the device's speed cancels), with its
/// quartiles as the spread. A ratio of the medians would mix frames from different path positions; it
/// is the fallback only where frames do not pair.
fn side_by_side(reports: &[BenchReport]) -> String {
    let mut s = String::from(
        "side by side (median GPU ms per frame; time ratio to the first row: median [quartiles] of the \
         per-frame ratios, the variants interleaved frame by frame):",
    );
    let base = &reports[0];
    for (i, r) in reports.iter().enumerate() {
        let ratio = match paired_ratios(&r.frame_totals, &base.frame_totals) {
            _ if i == 0 => "baseline".to_string(),
            Some([lo, mid, hi]) => format!("{mid:.3}x [{lo:.3}, {hi:.3}] {}", ratio_word(mid)),
            None => {
                let ratio = r.frame_total.median / base.frame_total.median;
                format!("{ratio:.3}x {} (ratio of the medians: frames do not pair)", ratio_word(ratio))
            }
        };
        s.push_str(&format!("\n  {:>10.3} ms  {ratio:<36} {}", r.frame_total.median, r.config));
    }
    s
}

/// What refitting costs in tree quality, and a CPU refit in time, over the benchmark's own animation
/// frames: each skinned instance's tree is built at the first frame, refit at each later one and
/// compared with a fresh build for that frame (SAH cost ratio) and by the bounds' area growth the
/// rebuild policy watches. None without skinned instances.
pub struct RefitQuality {
    /// Median host ms per frame of CPU skinning + triangle boxes + refit.
    pub cpu_refit_ms: f64,
    /// Worst and last SAH cost of the refit trees over fresh builds.
    pub worst_sah_ratio: f64,
    pub last_sah_ratio: f64,
    /// Largest bounds-area growth over the first frame's.
    pub worst_area_growth: f64,
}

fn refit_quality(job: &RenderJob, frames: usize) -> Result<Option<RefitQuality>> {
    use crate::accel::bvh::{triangle_aabbs, Bvh};
    use crate::accel::dynamic::area;
    let (mut scene, anim) = load_posed(job)?;
    let world = scene.world_matrices();
    let mut trees: Vec<(usize, Bvh, f32)> = Vec::new();
    for (i, inst) in scene.instances.iter().enumerate() {
        let Some(posed) = scene.skinned_pose(inst, &world) else { continue };
        let indices = &scene.meshes[inst.mesh].primitives[inst.primitive].indices;
        let bvh = Bvh::build(&triangle_aabbs(&posed, indices));
        let a = area(&bvh.root_bounds());
        trees.push((i, bvh, a));
    }
    if trees.is_empty() {
        return Ok(None);
    }
    let (mut times, mut worst, mut last, mut growth) = (Vec::new(), 1.0f64, 1.0f64, 1.0f64);
    for f in 1..frames.max(2) {
        if let Some(a) = anim {
            scene.animate(a, job.time + f as f32 / job.fps.max(1e-3));
        }
        let world = scene.world_matrices();
        let t0 = std::time::Instant::now();
        let mut boxes = Vec::new();
        for (i, bvh, _) in &mut trees {
            let inst = &scene.instances[*i];
            let posed = scene.skinned_pose(inst, &world).unwrap_or_default();
            let aabbs = triangle_aabbs(&posed, &scene.meshes[inst.mesh].primitives[inst.primitive].indices);
            bvh.refit(&aabbs);
            boxes.push(aabbs);
        }
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        let (mut refit_cost, mut fresh_cost) = (0.0f64, 0.0f64);
        for ((_, bvh, a0), aabbs) in trees.iter().zip(&boxes) {
            // SAH costs are normalised by the root area: weigh back by it.
            let a = area(&bvh.root_bounds()) as f64;
            refit_cost += bvh.sah_cost() as f64 * a;
            fresh_cost += Bvh::build(aabbs).sah_cost() as f64 * a;
            growth = growth.max(a / (*a0 as f64).max(1e-30));
        }
        last = refit_cost / fresh_cost.max(1e-30);
        worst = worst.max(last);
    }
    times.sort_by(f64::total_cmp);
    Ok(Some(RefitQuality {
        cpu_refit_ms: times[times.len() / 2],
        worst_sah_ratio: worst,
        last_sah_ratio: last,
        worst_area_growth: growth,
    }))
}
