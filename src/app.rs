//! The program's commands (`info`, `render`, `bench`), callable from the CLI
//! and from tests in-process.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk as avk;
use glam::Vec3;

use crate::accel::dynamic::RebuildPolicy;
use crate::render::shading::{Backend, Effects, Mode, SceneNeeds, ShadingConfig};
use crate::render::supersample::{self, Supersample};
use crate::render::{FrameOutput, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
use crate::vk::{Context, ContextOptions, DeviceSelector};

/// The bundled default scene, looked for in the working directory, next to
/// the executable (an installed copy, or `target/<profile>/` inside the
/// source tree), and in the source tree the binary was built from.
pub fn default_scene_path() -> Result<PathBuf> {
    const REL: &str = "assets/default.toml";
    let mut candidates = vec![PathBuf::from(REL)];
    if let Some(dir) = std::env::current_exe().ok().and_then(|e| e.parent().map(Path::to_path_buf)) {
        candidates.push(dir.join(REL));
        candidates.push(dir.join("../..").join(REL));
    }
    candidates.push(PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/default.toml")));
    let path = find_default_scene(&candidates)?;
    log::info!("default scene {}", path.display());
    Ok(path)
}

/// The first of `candidates` that exists; else an error listing where it
/// looked and pointing to `--scene`.
pub fn find_default_scene(candidates: &[PathBuf]) -> Result<PathBuf> {
    if let Some(p) = candidates.iter().find(|p| p.is_file()) {
        return Ok(p.clone());
    }
    let looked: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
    bail!(
        "the default scene assets/default.toml was not found (looked at {}); pass a scene with --scene PATH",
        looked.join(", ")
    )
}

/// Options shared by every command that touches the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    pub validation: bool,
    pub sync_validation: bool,
    pub device: DeviceSelector,
    pub disable_ray_tracing: bool,
}

impl GpuOptions {
    pub fn context(&self) -> Result<Context> {
        Context::new(&ContextOptions {
            validation: self.validation,
            sync_validation: self.sync_validation,
            device: self.device.clone(),
            disable_ray_tracing: self.disable_ray_tracing,
            surface_extensions: Vec::new(),
            swapchain: false,
        })
    }
}

/// Which camera a render uses.
#[derive(Clone, Debug, Default)]
pub enum CameraChoice {
    /// The scene's first camera (or the framing default).
    #[default]
    First,
    Index(usize),
    LookAt {
        from: Vec3,
        to: Vec3,
        yfov_deg: f32,
    },
}

impl CameraChoice {
    pub fn resolve(&self, scene: &Scene) -> Result<Camera> {
        match self {
            CameraChoice::First => Ok(scene.cameras[0].clone()),
            CameraChoice::Index(i) => scene.cameras.get(*i).cloned().with_context(|| {
                format!(
                    "camera {i} does not exist ({} has {} cameras)",
                    scene.source.display(),
                    scene.cameras.len()
                )
            }),
            CameraChoice::LookAt { from, to, yfov_deg } => {
                if (*from - *to).length_squared() == 0.0 || !from.is_finite() || !to.is_finite() {
                    bail!("--look-from and --look-at must be finite and different");
                }
                let radius = scene.bounds.extent().length().max(1e-6);
                let znear = (radius * 1e-4).max((from.distance(*to)) * 1e-4).max(1e-6);
                Ok(Camera::look_at("command line", *from, *to, yfov_deg.to_radians(), znear))
            }
        }
    }
}

#[derive(Clone, Debug)]
pub struct RenderJob {
    pub scene: PathBuf,
    pub width: u32,
    pub height: u32,
    pub camera: CameraChoice,
    pub settings: RenderSettings,
    /// glTF animation to play (name or index), if any.
    pub animation: Option<String>,
    /// Animation time in seconds for a single frame (`render`).
    pub time: f32,
    /// Fixed animation step for benchmarks: frame i is at time i / fps.
    pub fps: f32,
    /// `render --supersample K`: K×K samples per pixel, filtered down.
    pub supersample: Option<Supersample>,
}

impl RenderJob {
    pub fn new(scene: impl Into<PathBuf>, width: u32, height: u32) -> RenderJob {
        RenderJob {
            scene: scene.into(),
            width,
            height,
            camera: CameraChoice::First,
            settings: RenderSettings::default(),
            animation: None,
            time: 0.0,
            fps: 30.0,
            supersample: None,
        }
    }

    pub(crate) fn extent(&self) -> Result<avk::Extent2D> {
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            bail!("resolution {}x{} out of range (1..=16384)", self.width, self.height);
        }
        Ok(avk::Extent2D { width: self.width, height: self.height })
    }
}

/// Loads, uploads and renders one frame; returns it with the context's
/// validation error count.
/// Loads the job's scene; with an animation, also returns its index (the
/// scene is posed at `job.time`).
pub(crate) fn load_posed(job: &RenderJob) -> Result<(Scene, Option<usize>)> {
    let mut scene = Scene::load(&job.scene)?;
    let anim = match &job.animation {
        Some(a) => {
            let i = crate::scene::animation::find_animation(&scene, a)
                .with_context(|| format!("--animation {a}"))?;
            scene.animate(i, job.time);
            Some(i)
        }
        None => None,
    };
    Ok((scene, anim))
}

/// The shading configuration for `settings`; a backend that `--no-rt`
/// switched off is reported as such, not as missing from the device.
pub fn resolve_shading(ctx: &Context, scene: &Scene, settings: &RenderSettings) -> Result<ShadingConfig> {
    ShadingConfig::resolve(ctx, SceneNeeds::of(scene), settings).map_err(|e| {
        // The capabilities say what the device has, `rt` what was enabled.
        let disabled = match settings.backend {
            Backend::Query => ctx.caps.ray_query && !ctx.rt.ray_query,
            Backend::Pipeline => ctx.caps.ray_tracing_pipeline && !ctx.rt.ray_tracing_pipeline,
            _ => false,
        };
        if disabled {
            anyhow!(
                "--backend {}: the device supports it, but the ray-tracing extensions are disabled by --no-rt \
                 (drop --no-rt, or use --backend compute)",
                format!("{:?}", settings.backend).to_lowercase()
            )
        } else {
            e
        }
    })
}

pub fn render_once(ctx: &Context, job: &RenderJob) -> Result<FrameOutput> {
    let extent = job.extent()?;
    let (scene, _) = load_posed(job)?;
    let camera = job.camera.resolve(&scene)?;
    resolve_shading(ctx, &scene, &job.settings)?;
    if let Some(ss) = &job.supersample {
        return supersample::render_supersampled(ctx, &scene, &camera, extent, &job.settings, ss);
    }
    let mut renderer = Renderer::new(ctx, &scene, extent)?;
    let out = renderer.render(ctx, &scene, &camera, &job.settings);
    renderer.destroy(ctx);
    if let Some(w) = out.as_ref().ok().and_then(FrameOutput::truncation_warning) {
        log::warn!("{w}");
    }
    out
}

/// `render`: one frame to PNG (and optionally linear HDR). With `strict`,
/// non-finite pixels fail the command (after the images are written).
pub fn render_command(
    gpu: &GpuOptions,
    job: &RenderJob,
    out: &Path,
    hdr_out: Option<&Path>,
    strict: bool,
) -> Result<()> {
    with_context(gpu, |ctx| {
        let frame = render_once(ctx, job)?;
        print_timings(&frame.timings);
        let written = write_outputs(&frame, out, hdr_out, strict);
        // A validation error explains a broken frame better than its pixels.
        check_validation(ctx)?;
        written.map(|_| ())
    })
}

/// Runs `f` with a new context, then destroys the context and fails if the
/// validation layer reported anything during its life or teardown (objects
/// leaked at vkDestroyDevice), on the error path too: an error exit must
/// leave nothing behind either.
pub fn with_context<R>(gpu: &GpuOptions, f: impl FnOnce(&Context) -> Result<R>) -> Result<R> {
    let ctx = gpu.context()?;
    let result = f(&ctx);
    match (result, ctx.finish()) {
        (Ok(v), Ok(())) => Ok(v),
        (Err(e), Ok(())) | (Ok(_), Err(e)) => Err(e),
        (Err(e), Err(teardown)) => Err(e.context(format!("{teardown:#}"))),
    }
}

/// Pixels whose radiance has a NaN or Inf component: how many, and the
/// first one (x, y) in row order.
pub fn non_finite_pixels(frame: &FrameOutput) -> (usize, Option<(u32, u32)>) {
    let mut first = None;
    let mut count = 0;
    for (i, p) in frame.hdr.chunks_exact(4).enumerate() {
        if !p.iter().all(|v| v.is_finite()) {
            count += 1;
            first = first.or(Some((i as u32 % frame.width, i as u32 / frame.width)));
        }
    }
    (count, first)
}

/// Writes the frame; non-finite pixels are logged and written marked
/// (magenta in the PNG, 0 in the HDR) so they can be found, and fail only
/// with `strict`. Returns the number of non-finite pixels.
pub fn write_outputs(frame: &FrameOutput, out: &Path, hdr_out: Option<&Path>, strict: bool) -> Result<usize> {
    let (count, first) = non_finite_pixels(frame);
    let marked;
    let frame = match first {
        None => frame,
        Some((x, y)) => {
            log::warn!(
                "{count} pixel(s) with NaN or Inf radiance, the first at ({x}, {y}); \
                 written magenta in the PNG and 0 in the HDR"
            );
            let (mut ldr, mut hdr) = (frame.ldr.clone(), frame.hdr.clone());
            for (l, h) in ldr.chunks_exact_mut(4).zip(hdr.chunks_exact_mut(4)) {
                if !h.iter().all(|v| v.is_finite()) {
                    l.copy_from_slice(&[255, 0, 255, 255]);
                    h.copy_from_slice(&[0.0, 0.0, 0.0, 1.0]);
                }
            }
            marked = FrameOutput { ldr, hdr, timings: frame.timings.clone(), ..*frame };
            &marked
        }
    };
    frame.save_png(out)?;
    log::info!("wrote {} ({}x{})", out.display(), frame.width, frame.height);
    if let Some(h) = hdr_out {
        frame.save_hdr(h)?;
        log::info!("wrote {}", h.display());
    }
    if let (true, Some((x, y))) = (strict, first) {
        bail!("--strict: {count} pixel(s) of the rendered frame have NaN or Inf radiance, the first at ({x}, {y})");
    }
    Ok(count)
}

/// Fails when the validation layer reported an error during this run.
pub fn check_validation(ctx: &Context) -> Result<()> {
    let errors = ctx.validation_counters().errors();
    if errors > 0 {
        bail!("the Vulkan validation layer reported {errors} error(s); see the log above");
    }
    Ok(())
}

fn print_timings(t: &[(&'static str, f64)]) {
    let parts: Vec<_> = t.iter().map(|(n, ms)| format!("{n} {ms:.3} ms")).collect();
    log::info!("GPU: {}", parts.join(", "));
}

/// `info`: capability report of every device.
pub fn info_command(gpu: &GpuOptions) -> Result<String> {
    let instance = crate::vk::Instance::new(&crate::vk::InstanceOptions {
        validation: gpu.validation,
        ..Default::default()
    })?;
    let devices = crate::vk::device::enumerate(&instance.raw)?;
    if devices.is_empty() {
        bail!("no Vulkan device found");
    }
    let selected = crate::vk::device::select(&devices, &gpu.device).ok().map(|(_, c)| c.index);
    let mut s = String::new();
    if gpu.disable_ray_tracing {
        s.push_str("ray-tracing extensions disabled by --no-rt (what each device has is listed as is)\n");
    }
    for (_, c) in &devices {
        if gpu.disable_ray_tracing {
            s.push_str(&mark_disabled_rt(&c.report()));
        } else {
            s.push_str(&c.report());
        }
        if Some(c.index) == selected {
            s.push_str("  (selected)\n");
        }
    }
    Ok(s)
}

/// Appends "disabled by --no-rt" to the ray-tracing capabilities a device
/// report says yes to, so `info` matches what the commands will use.
fn mark_disabled_rt(report: &str) -> String {
    let rt_keys = ["  acceleration structures: yes", "  ray query: yes", "  ray-tracing pipeline: yes"];
    let mut s = String::new();
    for line in report.lines() {
        s.push_str(line);
        if rt_keys.contains(&line) {
            s.push_str(", disabled by --no-rt");
        }
        s.push('\n');
    }
    s
}

/// Per-pass statistics over a benchmark run.
#[derive(Clone, Debug)]
pub struct PassStats {
    pub name: &'static str,
    pub min: f64,
    pub median: f64,
    pub p95: f64,
    pub max: f64,
}

pub struct BenchReport {
    pub scene: PathBuf,
    pub device: String,
    /// The shading variant measured (mode, backend, effects).
    pub config: String,
    pub variant: BenchVariant,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub passes: Vec<PassStats>,
    pub frame_total: PassStats,
    /// Camera, shadow and secondary rays of the first camera's frame.
    pub rays_first_frame: [u32; 3],
}

impl BenchReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "scene {}  device {}  {}x{}  {} frames (GPU ms)\n{}\n{:<24} {:>9} {:>9} {:>9}\n",
            self.scene.display(),
            self.device,
            self.width,
            self.height,
            self.frames,
            self.config,
            "pass",
            "min",
            "median",
            "max"
        );
        for p in self.passes.iter().chain(std::iter::once(&self.frame_total)) {
            s.push_str(&format!("{:<24} {:>9.3} {:>9.3} {:>9.3}\n", p.name, p.min, p.median, p.max));
        }
        let [camera, shadow, secondary] = self.rays_first_frame;
        let total = (camera + shadow + secondary) as f64;
        if total > 0.0 {
            // Rays of the first frame over the median times of the passes
            // that trace them (they also shade, so this is a lower bound).
            let traced: Vec<&PassStats> =
                self.passes.iter().filter(|p| TRACING_PASSES.contains(&p.name)).collect();
            let trace_ms: f64 = traced.iter().map(|p| p.median).sum();
            s.push_str(&format!("rays/frame: camera {camera}, shadow {shadow}, secondary {secondary}"));
            if !traced.is_empty() {
                let names: Vec<_> = traced.iter().map(|p| p.name).collect();
                s.push_str(&format!(" -> {:.2} Mrays/s in {}", total / (trace_ms * 1e3), names.join(" + ")));
            }
            s.push('\n');
        }
        s
    }
}

/// The passes that may trace rays (camera, shadow, reflection/refraction).
const TRACING_PASSES: [&str; 3] = ["primary", "direct", "specular"];

fn stats(name: &'static str, mut v: Vec<f64>) -> PassStats {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len().max(1);
    PassStats {
        name,
        min: v.first().copied().unwrap_or(f64::NAN),
        median: v.get(n / 2).copied().unwrap_or(f64::NAN),
        p95: v.get(((0.95 * n as f64).ceil() as usize).clamp(1, n) - 1).copied().unwrap_or(f64::NAN),
        max: v.last().copied().unwrap_or(f64::NAN),
    }
}

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
) -> Result<BenchFrame> {
    let settings = RenderSettings { mode: variant.mode, backend: variant.backend, ..job.settings };
    renderer.rebuild_policy = match variant.accel {
        AccelUpdate::Policy => RebuildPolicy::default(),
        AccelUpdate::Refit => RebuildPolicy::NEVER,
        AccelUpdate::Rebuild | AccelUpdate::Full => RebuildPolicy::ALWAYS,
    };
    let t = if frames > 1 { (i.saturating_sub(warmup)) as f32 / (frames - 1) as f32 } else { 0.0 };
    let camera = crate::scene::camera::on_path(&scene.camera_path, t, base_camera);
    let mut update = Vec::new();
    let mut counts = [0; 2];
    if let Some(a) = anim {
        // Fixed-step clock: deterministic frames.
        scene.animate(a, job.time + i as f32 / job.fps.max(1e-3));
        if variant.accel == AccelUpdate::Full {
            renderer.rebuild_all_structures(ctx, scene)?;
        } else {
            renderer.update_scene(ctx, scene)?;
        }
        update = renderer.update_timings.clone();
        counts = renderer.update_counts;
    }
    let out = renderer.render(ctx, scene, &camera, &settings)?;
    if let Some(w) = out.truncation_warning().filter(|_| i == warmup) {
        log::warn!("{w}");
    }
    Ok(BenchFrame { update, timings: out.timings, counts })
}

/// `bench`: every variant is warmed up first (one ray-counting frame, then
/// `warmup` unmeasured frames along the path's start, so no variant absorbs
/// the process's warm-up), then each is measured over `frames` frames
/// along the scene's camera path (or from its camera), after one more
/// unmeasured frame when another variant ran in between. One renderer and
/// one scene upload for all; per-pass GPU times. Progress goes to stderr.
pub fn bench(
    ctx: &Context,
    job: &RenderJob,
    frames: usize,
    warmup: usize,
    variants: &[BenchVariant],
) -> Result<Vec<BenchReport>> {
    let extent = job.extent()?;
    let (mut scene, anim) = load_posed(job)?;
    let base_camera = job.camera.resolve(&scene)?;
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
    let mut renderer = Renderer::new(ctx, &scene, extent)?;
    let mut reports = Vec::new();
    let n = variants.len();
    let result: Result<()> = (|| {
        let mut rays = Vec::new();
        for (k, &v) in variants.iter().enumerate() {
            eprintln!(
                "bench: warming up {}/{n}: {:?} mode, {:?} backend, AS update {:?}",
                k + 1,
                v.mode,
                v.backend,
                v.accel
            );
            // One counted frame: the atomics would distort the timings.
            let settings = RenderSettings { mode: v.mode, backend: v.backend, ..job.settings };
            let counting =
                RenderSettings { effects: Effects { count_rays: true, ..settings.effects }, ..settings };
            rays.push(renderer.render(ctx, &scene, &base_camera, &counting)?.ray_counts);
            for i in 0..warmup {
                bench_frame(ctx, &mut renderer, &mut scene, anim, job, &base_camera, v, i, (warmup, frames))?;
            }
        }
        for (k, &v) in variants.iter().enumerate() {
            eprintln!("bench: measuring {}/{n} ({frames} frames)", k + 1);
            if n > 1 && warmup > 0 {
                // The frame's passes follow the variant: rebuilt since its warm-up.
                bench_frame(
                    ctx,
                    &mut renderer,
                    &mut scene,
                    anim,
                    job,
                    &base_camera,
                    v,
                    warmup - 1,
                    (warmup, frames),
                )?;
            }
            let mut per_pass: Vec<(&'static str, Vec<f64>)> = Vec::new();
            let mut totals = Vec::new();
            let mut counts = [0usize; 2];
            for i in warmup..warmup + frames {
                let f = bench_frame(
                    ctx,
                    &mut renderer,
                    &mut scene,
                    anim,
                    job,
                    &base_camera,
                    v,
                    i,
                    (warmup, frames),
                )?;
                counts = [counts[0] + f.counts[0], counts[1] + f.counts[1]];
                let mut total = 0.0;
                for &(name, ms) in f.update.iter().chain(&f.timings).filter(|(n, _)| *n != "readback") {
                    total += ms;
                    match per_pass.iter_mut().find(|(n, _)| *n == name) {
                        Some((_, v)) => v.push(ms),
                        None => per_pass.push((name, vec![ms])),
                    }
                }
                totals.push(total);
            }
            let c = renderer.shading_config().map(|c| c.describe()).unwrap_or_default();
            let config = match anim {
                Some(_) if v.accel == AccelUpdate::Full => {
                    format!("{c}; AS update: Full (every structure rebuilt every frame)")
                }
                Some(_) => format!(
                    "{c}; AS update: {:?} ({} refits, {} rebuilds of skinned structures)",
                    v.accel, counts[0], counts[1]
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
                passes: per_pass.into_iter().map(|(n, v)| stats(n, v)).collect(),
                frame_total: stats("frame", totals),
                rays_first_frame: rays[k],
            });
        }
        Ok(())
    })();
    renderer.destroy(ctx);
    result?;
    Ok(reports)
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

/// The tables of `reports` as CSV: one row per variant and pass (the
/// frame total last), GPU ms.
pub fn bench_csv(reports: &[BenchReport]) -> String {
    use crate::report::write::{csv_field, csv_number};
    let mut s = String::from(
        "variant,mode,backend,accel_update,config,pass,ms_min,ms_median,ms_p95,ms_max,frames,width,height,\
         rays_camera,rays_shadow,rays_secondary\n",
    );
    for (i, r) in reports.iter().enumerate() {
        let v = &r.variant;
        for p in r.passes.iter().chain(std::iter::once(&r.frame_total)) {
            let [c, sh, sec] = r.rays_first_frame;
            let row = [
                (i + 1).to_string(),
                format!("{:?}", v.mode).to_lowercase(),
                format!("{:?}", v.backend).to_lowercase(),
                format!("{:?}", v.accel).to_lowercase(),
                csv_field(&r.config),
                csv_field(p.name),
                csv_number(p.min, 4),
                csv_number(p.median, 4),
                csv_number(p.p95, 4),
                csv_number(p.max, 4),
                r.frames.to_string(),
                r.width.to_string(),
                r.height.to_string(),
                c.to_string(),
                sh.to_string(),
                sec.to_string(),
            ];
            s.push_str(&row.join(","));
            s.push('\n');
        }
    }
    s
}

/// "slower" / "faster" for a time ratio against the baseline.
pub fn ratio_word(ratio: f64) -> &'static str {
    if (ratio - 1.0).abs() < 0.005 {
        "as fast"
    } else if ratio > 1.0 {
        "slower"
    } else {
        "faster"
    }
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
        println!(
            "side by side (median GPU ms per frame; ratio to the first row, every variant warmed up first):"
        );
        let base = reports[0].frame_total.median;
        for (i, r) in reports.iter().enumerate() {
            let ratio = r.frame_total.median / base;
            let word = if i == 0 { "baseline" } else { ratio_word(ratio) };
            println!("  {:>10.3} ms  {ratio:>5.2}x {word:<8}  {}", r.frame_total.median, r.config);
        }
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

/// What refitting costs in tree quality, and what a CPU refit would cost in
/// time, over the benchmark's own animation frames: every skinned
/// instance's tree is built at the first frame and refit at each later one,
/// and compared with a tree freshly built for that frame (SAH cost ratio)
/// and the bounds' area growth the rebuild policy watches. None without
/// skinned instances.
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

/// Parses "x,y,z".
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("'{p}': {e}")))
        .collect::<Result<_, _>>()?;
    if v.len() != 3 {
        return Err(format!("expected x,y,z, got '{s}'"));
    }
    if !v.iter().all(|c| c.is_finite()) {
        return Err(format!("'{s}': coordinates must be finite"));
    }
    Ok(Vec3::new(v[0], v[1], v[2]))
}
