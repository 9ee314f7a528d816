//! The program's commands (`info`, `render`, `bench`), callable from the CLI and from tests in-process.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk as avk;
use glam::Vec3;

use crate::render::shading::{Backend, SceneNeeds, ShadingConfig};
use crate::render::supersample::{self, Supersample};
use crate::render::{FrameOutput, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
pub use crate::vk::GpuOptions;
use crate::vk::{Context, ContextOptions, RenderDocUse};

mod bench_tables;
mod benchmark;
mod budget_args;
pub mod cli_parse;
mod env_args;
mod gpu_args;
mod path_args;
mod rays;
mod view_args;
pub use bench_tables::*;
pub use benchmark::*;
pub use budget_args::BudgetArgs;
pub use env_args::{EnvArgs, EnvOverrides};
pub use gpu_args::GpuArgs;
pub use path_args::{PathArgs, MAX_PATH_SAMPLES};
pub use rays::{rays_command, KindReport, RayBench};
pub use view_args::{OnOff, ToneArgs, ViewArgs};

/// The bundled default scene, looked for in the working directory, next to the executable (an installed
/// copy, or `target/<profile>/` in the source tree), and in the source tree the binary was built from.
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

/// The first of `candidates` that exists; else an error listing where it looked and pointing to `--scene`.
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

impl GpuOptions {
    pub fn context(&self) -> Result<Context> {
        let renderdoc = if self.capture_frame.is_some() { RenderDocUse::Required } else { RenderDocUse::Off };
        Context::new(&ContextOptions {
            gpu: self.clone(),
            surface_extensions: Vec::new(),
            swapchain: false,
            renderdoc,
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
    /// --env, --env-rotation, --env-intensity.
    pub env: EnvOverrides,
}

impl RenderJob {
    pub fn new(scene: impl Into<PathBuf>, width: u32, height: u32) -> RenderJob {
        RenderJob {
            scene: scene.into(),
            width,
            height,
            camera: CameraChoice::First,
            // As the command line with no flags: the scene file's ambient applies.
            settings: RenderSettings { ambient_from_scene: true, ..RenderSettings::default() },
            animation: None,
            time: 0.0,
            fps: 30.0,
            supersample: None,
            env: EnvOverrides::default(),
        }
    }

    pub(crate) fn extent(&self) -> Result<avk::Extent2D> {
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            bail!("resolution {}x{} out of range (1..=16384)", self.width, self.height);
        }
        Ok(avk::Extent2D { width: self.width, height: self.height })
    }
}

/// Loads the job's scene; with an animation, also returns its index (the scene is posed at `job.time`).
pub(crate) fn load_posed(job: &RenderJob) -> Result<(Scene, Option<usize>)> {
    let mut scene = load_scene(job)?;
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

/// Loads the job's scene with the command line's environment overrides.
pub(crate) fn load_scene(job: &RenderJob) -> Result<Scene> {
    let mut scene = Scene::load(&job.scene)?;
    job.env.apply(&mut scene)?;
    Ok(scene)
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
    // Progress for a long load: scene, upload, structures, the first frame's shaders.
    let mut load = Some(crate::progress::begin());
    let extent = job.extent()?;
    let (scene, _) = load_posed(job)?;
    let camera = job.camera.resolve(&scene)?;
    resolve_shading(ctx, &scene, &job.settings)?;
    if let Some(ss) = &job.supersample {
        return supersample::render_supersampled(ctx, &scene, &camera, extent, &job.settings, ss);
    }
    let mut renderer = Renderer::new(ctx, &scene, extent)?;
    // With --capture-frame N the same view is rendered N + 1 times and
    // frame N captured (frame 0 also compiles pipelines and builds targets).
    let frames = ctx.capture_frame.map_or(1, |n| n + 1);
    let mut out = Err(anyhow!("no frame rendered"));
    for i in 0..frames {
        out = ctx.capture_frame_if(i, &format!("render frame {i}"), || {
            // (Without --reference-samples one frame.)
            crate::render::reference::render_converged(&mut renderer, ctx, &scene, &camera, &job.settings)
        });
        load.take();
        if out.is_err() {
            break;
        }
    }
    if let Some(b) = renderer.budget_report() {
        log::info!("{}", b.summary());
    }
    renderer.destroy(ctx);
    if let Ok(frame) = &out {
        log_frame_health(frame);
    }
    out
}

/// Logs what the frame's counters and exposure state say: cut
/// reflection/refraction trees, NaN/Inf pixels, the measured exposure.
pub fn log_frame_health(frame: &FrameOutput) {
    if let Some(w) = frame.truncation_warning() {
        log::warn!("{w}");
    }
    if frame.bad_pixels > 0 {
        log::warn!(
            "{} pixel(s) reached tone mapping with NaN or Inf radiance: shown magenta, left out of the \
             exposure measurement",
            frame.bad_pixels
        );
    }
    if let Some(e) = frame.exposure {
        log::info!(
            "auto exposure: log-average luminance {:.4e}, target {:.4e}, adapted {:.4e}, exposure {:.4e}, \
             max luminance {:.4e} ({} finite pixels)",
            e.log_average,
            e.target,
            e.adapted,
            e.exposure,
            e.max_luminance,
            e.finite_pixels
        );
    }
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
        if frame.cold && ctx.caps.device_type == ash::vk::PhysicalDeviceType::CPU {
            log::info!(
                "GPU: these are the passes' first frame: on a software device they include compiling the \
                 shaders (bench warms up before it measures)"
            );
        }
        let written = write_outputs(&frame, out, hdr_out, strict);
        // A validation error explains a broken frame better than its pixels.
        check_validation(ctx)?;
        written.map(|_| ())
    })
}

/// The ray backends the device offers: compute where compute shaders have subgroup ballots, query and
/// pipeline where the driver's extensions are enabled.
pub fn offered_backends(gpu: &GpuOptions) -> Result<Vec<Backend>> {
    with_context(gpu, |ctx| {
        let accel = ctx.rt.acceleration_structure;
        Ok([
            (Backend::Compute, ctx.caps.subgroup_ops),
            (Backend::Query, accel && ctx.rt.ray_query),
            (Backend::Pipeline, accel && ctx.rt.ray_tracing_pipeline),
        ]
        .into_iter()
        .filter(|(_, on)| *on)
        .map(|(b, _)| b)
        .collect())
    })
}

/// Runs `f` with a new context, then destroys it and fails if the validation layer reported anything
/// during its life or teardown (objects leaked at vkDestroyDevice), on the error path too: an error exit
/// must leave nothing behind either.
pub fn with_context<R>(gpu: &GpuOptions, f: impl FnOnce(&Context) -> Result<R>) -> Result<R> {
    let ctx = gpu.context()?;
    let result = f(&ctx);
    match (result, ctx.finish()) {
        (Ok(v), Ok(())) => Ok(v),
        (Err(e), Ok(())) | (Ok(_), Err(e)) => Err(e),
        (Err(e), Err(teardown)) => Err(e.context(format!("{teardown:#}"))),
    }
}

/// Pixels whose radiance has a NaN or Inf component: how many, and the first one (x, y) in row order.
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

/// Writes the frame; non-finite pixels are logged and written marked (magenta in the PNG, 0 in the HDR) so
/// they can be found, and fail only with `strict`. Returns the number of non-finite pixels.
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
        max_api_version: gpu.max_api_version,
        ..Default::default()
    })?;
    let devices = crate::vk::device::enumerate(&instance.raw, instance.api_version)?;
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
