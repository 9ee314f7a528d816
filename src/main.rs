//! Command line: `info`, `render`, `bench`, `report`, `compare`, `view`. With no command it opens
//! the viewer on the bundled default scene when a display is available, else
//! renders it headless to `out/default.png`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context as _, Result};
use clap::{error::ErrorKind, Args, CommandFactory, Parser, Subcommand};
use glam::Vec3;

use hybrid_rt::app::cli_parse::*;
use hybrid_rt::app::{self, AccelUpdate, CameraChoice, GpuOptions, RenderJob};
use hybrid_rt::render::rays::Traversal;
use hybrid_rt::render::settings::PrimaryVisibility;
use hybrid_rt::render::shading::{AaMode, Backend, Effects, Mode};
use hybrid_rt::render::supersample::{SampleFilter, Supersample};
use hybrid_rt::render::tone::{AutoExposure, ToneOperator, ToneSettings};
use hybrid_rt::render::{DebugView, RenderSettings};
use hybrid_rt::report::{self, ReferenceSettings, ReportOptions};
use hybrid_rt::viewer::{self, PresentMode, ViewerOptions};
use hybrid_rt::vk::DeviceSelector;

#[derive(Parser)]
#[command(name = "hybrid-rt", version, about = "Hybrid rasterization + ray-tracing renderer (Vulkan)")]
struct Cli {
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Args)]
struct GpuArgs {
    /// Enable VK_LAYER_KHRONOS_validation; any validation error makes the
    /// command fail. Also on with HYBRID_RT_VALIDATION=1.
    #[arg(long, global = true)]
    validation: bool,
    /// With --validation: also run synchronization validation.
    #[arg(long, global = true)]
    sync_validation: bool,
    /// Device: index from `info`, a name substring, or "auto" (prefers a discrete GPU).
    #[arg(long, global = true, default_value = "auto")]
    device: String,
    /// Do not enable any ray-tracing extension even if the device has them.
    #[arg(long, global = true)]
    no_rt: bool,
    /// Do not enable VK_KHR_ray_query even if the device has it: the path of
    /// drivers that offer only the ray-tracing pipeline.
    #[arg(long, global = true)]
    no_ray_query: bool,
    /// Highest Vulkan API version to use (1.2 or 1.3): 1.2 takes the path a
    /// 1.2 device takes (RenderDoc 1.24 shows lavapipe as one), the 1.3
    /// features through their extensions.
    #[arg(long, global = true, value_parser = parse_vulkan_api)]
    vulkan_api: Option<u32>,
    /// Log level (error, warn, info, debug, trace); RUST_LOG overrides.
    #[arg(long, global = true, default_value = "info")]
    log: String,
}

#[derive(Subcommand)]
enum Command {
    /// List Vulkan devices and what they support (ray query, RT pipeline, ...).
    Info,
    /// Render one frame offscreen to a PNG.
    Render {
        #[command(flatten)]
        view: ViewArgs,
        /// Output PNG (tone-mapped sRGB).
        #[arg(long, default_value = "out/render.png")]
        out: PathBuf,
        /// Also write linear radiance as Radiance .hdr.
        #[arg(long)]
        hdr_out: Option<PathBuf>,
        /// Fail (after writing) when a pixel is NaN or Inf; without it such
        /// pixels are logged and written marked (magenta PNG, 0 HDR).
        #[arg(long)]
        strict: bool,
        /// Capture frame N (0-based; the view is rendered N + 1 times) with RenderDoc's in-application API
        /// (under `renderdoccmd capture`, or with librenderdoc.so loadable);
        /// the log names the capture file.
        #[arg(long, value_name = "N")]
        capture_frame: Option<u64>,
        /// Render K×K samples per pixel (1..=16) at K·W x K·H and filter
        /// them down: a reference to measure anti-aliasing against (the
        /// large frame is not post-filtered: no --aa).
        #[arg(long, value_parser = parse_supersample, allow_hyphen_values = true)]
        supersample: Option<u32>,
        /// With --supersample: how the samples of a pixel are weighted [default: box].
        #[arg(long, value_enum, requires = "supersample")]
        ss_filter: Option<SampleFilter>,
    },
    /// Render N frames along the scene's camera path; print per-pass GPU times.
    Bench {
        #[command(flatten)]
        view: ViewArgs,
        /// Measured frames (>= 1).
        #[arg(long, default_value_t = 60, value_parser = parse_count, allow_hyphen_values = true)]
        frames: usize,
        /// Frames rendered first and not measured (shader JIT, caches).
        #[arg(long, default_value_t = 3)]
        warmup: usize,
        /// Measure hybrid and pure ray tracing side by side in this run.
        #[arg(long)]
        compare_modes: bool,
        /// Measure every ray backend the device offers side by side.
        #[arg(long)]
        compare_backends: bool,
        /// How animated frames update the acceleration structures.
        #[arg(long, value_enum, default_value_t = AccelUpdate::Policy)]
        accel_update: AccelUpdate,
        /// Measure refit, rebuild and full rebuild side by side.
        #[arg(long)]
        compare_accel_updates: bool,
        /// Also write the tables as CSV (one row per variant and pass).
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Ray microbenchmark instead of frames: primary rays (one per pixel of
        /// --width x --height from the scene camera), shadow rays to the first light
        /// and cosine-sampled diffuse rays from the primary hits, traced by the compute
        /// BVH tracer and the driver's tracer (--backend query or pipeline; auto: the
        /// ray query, else the pipeline); prints Mrays/s per kind, their mismatches
        /// and the compute tracer's node and triangle tests per ray.
        #[arg(long, conflicts_with_all = ["compare_modes", "compare_backends", "compare_accel_updates", "csv", "capture_frame"])]
        rays: bool,
        /// With --rays: timed repetitions per ray set (after one untimed).
        #[arg(long, default_value_t = 5, value_parser = parse_reps, allow_hyphen_values = true, requires = "rays")]
        ray_reps: usize,
        /// With --rays: the compute tracer's traversal (default: per ray kind as the
        /// tracing passes use it; lane: every ray on its own; packet: the subgroup's
        /// rays walk one node sequence together).
        #[arg(long, value_enum, default_value_t = Traversal::Default, requires = "rays")]
        ray_traversal: Traversal,
        /// Capture frame N (0-based, in the order rendered: per variant the ray-counting
        /// frame and the warm-up, then the measured frames) with RenderDoc's in-application API
        /// (under `renderdoccmd capture`, or with librenderdoc.so loadable);
        /// the log names the capture file.
        #[arg(long, value_name = "N")]
        capture_frame: Option<u64>,
    },
    /// Image error (ꟻLIP, PSNR) against GPU time for every quality knob:
    /// report.md, report.csv, error_vs_time.png and error maps in --out.
    Report {
        #[command(flatten)]
        view: ViewArgs,
        /// Timed frames per setting (>= 5), after the warm-up.
        #[arg(long, default_value_t = 10, value_parser = parse_count, allow_hyphen_values = true)]
        frames: usize,
        /// Unmeasured frames per setting before timing (>= 1; the first
        /// compiles the setting's pipelines).
        #[arg(long, default_value_t = 2, value_parser = parse_count, allow_hyphen_values = true)]
        warmup: usize,
        /// Knobs to sweep, comma-separated, each optionally with its values
        /// after '=' separated by ':' (e.g. "max-depth=0:2:8,mode"); knobs:
        /// max-depth, min-weight, effects, mode, backend, aa, accel-update
        /// (animated scenes: with --animation, frames --fps apart), budget
        /// (share of the cost of tracing everything), resolution-scale.
        /// Default: all, with their full value lists.
        #[arg(long)]
        knobs: Option<String>,
        /// What every knob is measured against: path (the path-traced ground
        /// truth, --ref-samples, cached on disk) or self (this renderer at
        /// its deepest settings: --ref-mode, --ref-max-depth, --ref-min-weight).
        #[arg(long = "ref", value_enum, default_value_t = RefKind::Path)]
        ref_kind: RefKind,
        /// --ref path: paths per pixel to start with (doubled while the
        /// reference's own noise is over half the smallest error).
        #[arg(long, default_value_t = 256, value_parser = parse_ref_samples, allow_hyphen_values = true)]
        ref_samples: u32,
        /// --ref path: the most paths per pixel it may double to.
        #[arg(long, default_value_t = 4096, value_parser = parse_ref_samples, allow_hyphen_values = true)]
        ref_max_samples: u32,
        /// --ref path: cache directory [default: $HYBRID_RT_TRUTH_CACHE, else
        /// $XDG_CACHE_HOME/hybrid-rt/truth, else ~/.cache/hybrid-rt/truth].
        #[arg(long, value_name = "DIR", conflicts_with = "no_ref_cache")]
        ref_cache: Option<PathBuf>,
        /// --ref path: render the reference even if a cached one exists, and cache nothing.
        #[arg(long)]
        no_ref_cache: bool,
        /// --ref path: samples per pixel of each term of the default frame's
        /// error attribution (0 leaves it out).
        #[arg(long, default_value_t = 256)]
        attribution_samples: u32,
        /// --ref self: maximum recursion depth (pure-RT mode, every effect).
        #[arg(long, default_value_t = 16, value_parser = parse_max_depth, allow_hyphen_values = true)]
        ref_max_depth: u32,
        /// --ref self: importance cutoff in [0, 1].
        #[arg(long, default_value_t = 0.001, value_parser = parse_min_weight, allow_hyphen_values = true)]
        ref_min_weight: f32,
        /// Reference: ray backend [default: the --backend of the base settings].
        #[arg(long, value_enum)]
        ref_backend: Option<Backend>,
        /// --ref self: rt (camera rays traced) or hybrid (then the rows leave
        /// out the hybrid-vs-rt difference the self-check reports).
        #[arg(long, value_enum, default_value_t = Mode::Rt)]
        ref_mode: Mode,
        /// Do not count rays per frame (saves a pipeline compile per setting).
        #[arg(long)]
        no_ray_counts: bool,
        /// The aa knob's reference: the base settings with K×K samples per
        /// pixel (1..=16).
        #[arg(long, default_value_t = 4, value_parser = parse_supersample, allow_hyphen_values = true)]
        ref_supersample: u32,
        /// How the aa knob's reference weighs its samples.
        #[arg(long, value_enum, default_value_t = SampleFilter::Box)]
        ref_ss_filter: SampleFilter,
        /// Numerical-stability report instead: stiff and extreme variants
        /// of the scene (moved far from the origin, scaled, grazing and
        /// facing mirrors, IOR near 1, a 1e5 environment texel, ...) on
        /// every available backend, with pass/fail thresholds.
        #[arg(long, conflicts_with_all = ["knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts", "ref_supersample", "ref_ss_filter"])]
        stability: bool,
        /// With --stability: only these cases (comma-separated; the
        /// canonicals they are compared with are added), e.g.
        /// "translate-1e3,ior-1.0".
        #[arg(long, requires = "stability", value_delimiter = ',')]
        cases: Vec<String>,
        /// The ray-tracing budget along the scene's camera path instead:
        /// paper mode, effects mode and effects mode with the raster
        /// fallback at these shares of the cost of tracing
        /// everything (comma-separated in [0, 1]), --frames points along
        /// the path after --warmup frames at its start; frame ms, heuristic
        /// share and ꟻLIP/PSNR against full effects per run, table + plot.
        #[arg(long, value_delimiter = ',', value_parser = parse_share, conflicts_with_all = ["stability", "knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts", "tone_sheet"])]
        budget_paths: Vec<f64>,
        /// Tone operators side by side instead: a contact sheet per Radiance
        /// .hdr map (comma-separated), the scene lit by each; rows operators,
        /// columns key values (log-average auto exposure) and the fixed
        /// --exposure; tone_sheet.md with the measured exposures and pass ms.
        #[arg(long, value_delimiter = ',', conflicts_with_all = ["stability", "knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts"])]
        tone_sheet: Vec<PathBuf>,
        /// The environment light's ambient instead (SH irradiance and
        /// diffuse PRT) against a ray-traced reference of the view
        /// (--reference-samples N (1024) --reference-bounces K (3 here)); --knobs
        /// picks among bands, sh-samples, transfer, whose product runs.
        #[arg(long, conflicts_with_all = ["stability", "budget_paths", "tone_sheet", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "ref_supersample", "ref_ss_filter"])]
        prt: bool,
        /// With --prt: one knob at a time around the base settings instead
        /// of the product.
        #[arg(long, requires = "prt")]
        prt_sweep: bool,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
    },
    /// Compare two images (PNG with PNG, or Radiance .hdr with .hdr; A is the
    /// reference): prints ꟻLIP mean, PSNR and the share of pixels over a
    /// ꟻLIP threshold; --out writes the per-pixel error map.
    Compare {
        /// Reference image.
        a: PathBuf,
        /// Test image.
        b: PathBuf,
        /// Write the ꟻLIP error map (magma colour map) to this PNG.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Per-pixel ꟻLIP error counted as visible above this, in [0, 1].
        #[arg(long, default_value_t = 0.1, value_parser = parse_min_weight, allow_hyphen_values = true)]
        threshold: f32,
        /// .hdr inputs: exposure both are tone-mapped with for ꟻLIP.
        #[arg(long, default_value_t = 1.0, value_parser = parse_exposure, allow_hyphen_values = true)]
        exposure: f32,
    },
    /// Open an interactive window (fly/orbit camera, debug views, screenshots).
    #[command(after_long_help = hybrid_rt::viewer::keys::help())]
    View {
        #[command(flatten)]
        view: ViewArgs,
        /// Swapchain present mode (falls back to fifo when unsupported).
        #[arg(long, value_enum, default_value_t = PresentMode::Fifo)]
        present_mode: PresentMode,
        /// Exit after presenting N frames (>= 1).
        #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
        frames: Option<usize>,
        /// With --frames: write the last frame to this PNG. Without: where P / F12 write.
        #[arg(long)]
        screenshot: Option<PathBuf>,
        /// Test automation: resize the window twice, minimize and restore it.
        #[arg(long, hide = true)]
        test_resize: bool,
        /// Capture presented frame N (0-based; F9 captures the next frame
        /// whenever the viewer runs under RenderDoc) with RenderDoc's in-application API
        /// (under `renderdoccmd capture`, or with librenderdoc.so loadable);
        /// the log names the capture file.
        #[arg(long, value_name = "N")]
        capture_frame: Option<u64>,
    },
}

#[derive(Args, Clone)]
struct ViewArgs {
    /// glTF/GLB, OBJ or TOML scene file (default: assets/default.toml, in
    /// the working directory, next to the executable or in the source tree).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Image width in pixels (1..=16384).
    #[arg(long, default_value_t = 1280, value_parser = parse_resolution, allow_hyphen_values = true)]
    width: u32,
    /// Image height in pixels (1..=16384).
    #[arg(long, default_value_t = 720, value_parser = parse_resolution, allow_hyphen_values = true)]
    height: u32,
    /// Index of the scene camera to use.
    #[arg(long, conflicts_with = "look_from")]
    camera: Option<usize>,
    /// Camera position "x,y,z" (finite; with --look-at).
    #[arg(long, value_parser = app::parse_vec3, requires = "look_at", allow_hyphen_values = true)]
    look_from: Option<Vec3>,
    /// Camera target "x,y,z" (finite; with --look-from).
    #[arg(long, value_parser = app::parse_vec3, requires = "look_from", allow_hyphen_values = true)]
    look_at: Option<Vec3>,
    /// Vertical field of view in degrees, in (0, 180), for --look-from/--look-at [default: 60].
    #[arg(long, value_parser = parse_fov, allow_hyphen_values = true)]
    fov: Option<f32>,
    /// Exposure multiplier before tone mapping (finite, > 0); with
    /// --auto-exposure, a compensation on the measured exposure.
    #[arg(long, default_value_t = 1.0, value_parser = parse_exposure, allow_hyphen_values = true)]
    exposure: f32,
    #[command(flatten)]
    tone: ToneArgs,
    /// Show a G-buffer target instead of the lit image.
    #[arg(long, value_enum, default_value_t = DebugView::None)]
    debug_view: DebugView,
    /// hybrid: G-buffer primary hits + traced secondary rays; rt: trace camera
    /// rays too; path: the path-traced ground truth (--samples).
    #[arg(long, value_enum, default_value_t = Mode::Hybrid)]
    mode: Mode,
    #[command(flatten)]
    path: app::PathArgs,
    /// Ray traversal backend.
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    backend: Backend,
    /// Hybrid mode's primary hits: raster (visibility buffer), traced
    /// (camera rays) or auto (view and bench: measure both per view, keep
    /// the cheaper; render: raster, so images do not depend on timing).
    #[arg(long, value_enum, default_value_t = PrimaryVisibility::Auto)]
    primary_visibility: PrimaryVisibility,
    /// Two-phase occlusion culling of the raster G-buffer's clusters (the
    /// image is the same; off by default: the shipped camera paths hide
    /// almost nothing, see README).
    #[arg(long, value_enum, default_value_t = OnOff::Off)]
    occlusion_culling: OnOff,
    /// Anti-aliasing after tone mapping: edge (G-buffer depth and normal
    /// discontinuities), fxaa (luminance edges) or none [default: edge].
    #[arg(long, value_enum)]
    aa: Option<AaMode>,
    /// Trace no shadow rays: punctual lights reach every surface unoccluded.
    #[arg(long)]
    no_shadows: bool,
    /// Trace no mirror reflections (surfaces up to roughness 0.35 then get
    /// the ambient term's specular share instead).
    #[arg(long)]
    no_reflections: bool,
    /// Trace no refractions: transmissive surfaces show only their
    /// reflection and ambient terms.
    #[arg(long)]
    no_refractions: bool,
    /// Maximum reflection/refraction recursion depth (0..=64).
    #[arg(long, default_value_t = 8, value_parser = parse_max_depth, allow_hyphen_values = true)]
    max_depth: u32,
    /// Importance cutoff in [0, 1]: branches with a smaller weight are not traced.
    #[arg(long, default_value_t = 0.01, value_parser = parse_min_weight, allow_hyphen_values = true)]
    min_weight: f32,
    /// glTF animation to play, by name or index.
    #[arg(long)]
    animation: Option<String>,
    /// Animation time in seconds, finite, with --animation (render: the
    /// frame's time; bench and view: the start) [default: 0].
    #[arg(long, value_parser = parse_time, allow_hyphen_values = true)]
    time: Option<f32>,
    /// Fixed animation step (finite, > 0), with --animation: frame i is at
    /// time + i / fps (bench: 30 when not given; view: wall-clock playback
    /// when not given).
    #[arg(long, value_parser = parse_fps, allow_hyphen_values = true)]
    fps: Option<f32>,
    #[command(flatten)]
    budget: app::BudgetArgs,
    #[command(flatten)]
    env: app::EnvArgs,
}

/// Tone mapping and auto exposure (render/tone.rs).
#[derive(Args, Clone)]
struct ToneArgs {
    /// Tone curve.
    #[arg(long, value_enum, default_value_t = ToneOperator::Reinhard)]
    tonemap: ToneOperator,
    /// Exposure from the frame's luminance: off (fixed --exposure),
    /// log-average (Reinhard's key / log-average), histogram (percentile-clipped
    /// log-luminance histogram). Still frames converge at once; bench and
    /// view adapt over time.
    #[arg(long, value_enum, default_value_t = AutoExposure::Off)]
    auto_exposure: AutoExposure,
    /// Key: the exposed luminance the frame's average maps to (finite, > 0),
    /// with --auto-exposure [default: 0.18].
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    key: Option<f32>,
    /// White point of --tonemap reinhard-white in exposed luminance (finite,
    /// > 0) [default: the frame's brightest pixel].
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    white_point: Option<f32>,
    /// Histogram auto exposure: the darkest and brightest fractions of
    /// pixels left out, "LOW,HIGH" with 0 <= LOW < HIGH <= 1 [default: 0.1,0.9].
    #[arg(long, value_parser = parse_percentiles, allow_hyphen_values = true)]
    histogram_clip: Option<(f32, f32)>,
    /// Histogram auto exposure: adaptation speeds in EV per second,
    /// "BRIGHTEN,DARKEN" (finite, > 0) [default: 3,1].
    #[arg(long, value_parser = parse_speeds, allow_hyphen_values = true)]
    adapt_speed: Option<(f32, f32)>,
}

impl ToneArgs {
    fn settings(&self) -> ToneSettings {
        let d = ToneSettings::default();
        let (histogram_low, histogram_high) =
            self.histogram_clip.unwrap_or((d.histogram_low, d.histogram_high));
        let (speed_brighten, speed_darken) = self.adapt_speed.unwrap_or((d.speed_brighten, d.speed_darken));
        ToneSettings {
            operator: self.tonemap,
            auto_exposure: self.auto_exposure,
            key: self.key.unwrap_or(d.key),
            white: self.white_point,
            histogram_low,
            histogram_high,
            speed_brighten,
            speed_darken,
        }
    }

    /// A tone option the chosen operator or exposure mode does not read.
    fn without_effect(&self) -> Option<&'static str> {
        let histogram = self.auto_exposure == AutoExposure::Histogram;
        if self.key.is_some() && self.auto_exposure == AutoExposure::Off {
            return Some("--key has no effect without --auto-exposure (the fixed --exposure applies)");
        }
        if self.white_point.is_some() && self.tonemap != ToneOperator::ReinhardWhite {
            return Some("--white-point has no effect without --tonemap reinhard-white");
        }
        if (self.histogram_clip.is_some() || self.adapt_speed.is_some()) && !histogram {
            return Some(
                "--histogram-clip and --adapt-speed have no effect without --auto-exposure histogram",
            );
        }
        None
    }
}

impl ViewArgs {
    /// Options that would change nothing here: refused (a usage error), so a
    /// typo'd or misplaced option is not silently ignored.
    fn without_effect(&self, command: &str) -> Option<String> {
        if let Some(why) = self.tone.without_effect() {
            return Some(why.into());
        }
        if self.fov.is_some() && self.look_from.is_none() {
            return Some(
                "--fov has no effect without --look-from/--look-at (scene cameras keep their own)".into(),
            );
        }
        if let Some(why) = self.budget.without_budget() {
            return Some(why.into());
        }
        if self.env.reference_samples.is_some() && self.debug_view != DebugView::None {
            return Some(
                "--reference-samples has no effect with --debug-view (it shows the G-buffer)".into(),
            );
        }
        if let Some(why) = self.path.without_effect(self.mode) {
            return Some(why.into());
        }
        if self.path.samples.is_some() && (command == "view" || command == "bench") {
            return Some(format!(
                "--samples has no effect on {command}: it adds 4 paths per pixel a frame while the view stays still"
            ));
        }
        if self.mode == Mode::Path {
            if self.env.reference_samples.is_some() {
                return Some(
                    "--reference-samples has no effect with --mode path (it traces everything)".into(),
                );
            }
            if self.aa.is_some_and(|a| a != AaMode::None) {
                return Some(
                    "--aa has no effect with --mode path: its jittered camera paths integrate each pixel"
                        .into(),
                );
            }
        }
        if self.time.is_some() && self.animation.is_none() {
            return Some("--time has no effect without --animation".into());
        }
        if self.fps.is_some() && self.animation.is_none() {
            return Some("--fps has no effect without --animation".into());
        }
        if self.fps.is_some() && command == "render" {
            return Some(
                "--fps has no effect on render (one frame at --time; it steps bench and view)".into(),
            );
        }
        None
    }

    fn job(&self) -> Result<RenderJob> {
        let camera = match (self.camera, self.look_from, self.look_at) {
            (Some(i), _, _) => CameraChoice::Index(i),
            (None, Some(from), Some(to)) => {
                CameraChoice::LookAt { from, to, yfov_deg: self.fov.unwrap_or(60.0) }
            }
            _ => CameraChoice::First,
        };
        let scene = match &self.scene {
            Some(s) => s.clone(),
            None => app::default_scene_path()?,
        };
        Ok(RenderJob {
            scene,
            width: self.width,
            height: self.height,
            camera,
            settings: RenderSettings {
                exposure: self.exposure,
                tone: self.tone.settings(),
                debug_view: self.debug_view,
                mode: self.mode,
                backend: self.backend,
                aa: self.aa.unwrap_or_default(),
                effects: Effects {
                    shadows: !self.no_shadows,
                    reflections: !self.no_reflections,
                    refractions: !self.no_refractions,
                    max_depth: self.max_depth,
                    min_weight: self.min_weight,
                    count_rays: false,
                },
                budget: self.budget.settings(),
                ambient: self.env.ambient.unwrap_or_default(),
                ambient_from_scene: self.env.ambient.is_none(),
                prt: self.env.prt_options(),
                reference: self.env.reference(),
                terms: 0,
                path: self.path.settings(),
                primary_visibility: self.primary_visibility,
                occlusion_culling: self.occlusion_culling == OnOff::On,
                ..RenderSettings::default()
            },
            animation: self.animation.clone(),
            time: self.time.unwrap_or(0.0),
            fps: self.fps.unwrap_or(30.0),
            supersample: None,
            env: self.env.overrides(),
        })
    }
}

impl Cli {
    /// Checks across options the parser cannot express; exits like a clap
    /// usage error (code 2).
    fn check_usage(&self) {
        let (name, view) = match &self.command {
            Some(Command::Render { view, .. }) => ("render", view),
            Some(Command::Bench { view, .. }) => ("bench", view),
            Some(Command::Report { view, .. }) => ("report", view),
            Some(Command::View { view, .. }) => ("view", view),
            Some(Command::Info) | Some(Command::Compare { .. }) | None => return,
        };
        let problem = match &self.command {
            Some(Command::Report { ref_kind: RefKind::Own, attribution_samples, .. }) if *attribution_samples != 256 => {
                Some("--attribution-samples measures against the path-traced truth: leave out --ref self".into())
            }
            Some(Command::Report { ref_kind: RefKind::Path, ref_mode, ref_max_depth, ref_min_weight, .. })
                if *ref_mode != Mode::Rt || *ref_max_depth != 16 || *ref_min_weight != 0.001 =>
            {
                Some(
                    "--ref-mode, --ref-max-depth and --ref-min-weight set the self reference: add --ref self \
                     (the default reference is the path-traced truth)"
                        .into(),
                )
            }
            Some(Command::Report { knobs, stability, tone_sheet, .. })
                if view.fps.is_some()
                    && (*stability
                        || !tone_sheet.is_empty()
                        || knobs.as_deref().is_some_and(|k| !k.contains("accel-update"))) =>
            {
                Some(
                    "--fps has no effect here: report renders still frames at --time; it steps only the \
                     accel-update knob's frames"
                        .into(),
                )
            }
            // (The other report modes read --knobs their own way.)
            Some(Command::Report { knobs: Some(k), prt: false, stability: false, tone_sheet, budget_paths, .. })
                if tone_sheet.is_empty() && budget_paths.is_empty() && report::knobs::parse_selection(k).is_err() =>
            {
                let e = report::knobs::parse_selection(k).expect_err("checked above");
                Some(format!("--knobs: {e:#}"))
            }
            Some(Command::Report { frames, stability: false, tone_sheet, budget_paths, .. })
                if *frames < 5 && tone_sheet.is_empty() && budget_paths.is_empty() =>
            {
                Some(format!("--frames {frames} is too few for a p95; use at least 5"))
            }
            Some(Command::Report { prt: false, .. }) if view.env.reference_samples.is_some() => Some(
                "--reference-samples is a report option only with --prt (the ambient's reference): report \
                 renders one frame per variant, and the reference needs ceil(N/4) (render it with `render \
                 --reference-samples N`, then `compare`)"
                    .into(),
            ),
            Some(Command::Render { supersample: Some(k), .. }) if view.env.reference_samples.is_some() => {
                Some(format!(
                    "--reference-samples does not combine with --supersample {k} (render the reference at the \
                     large size instead)"
                ))
            }
            Some(Command::Render { supersample: Some(k), .. }) if view.mode == Mode::Path => Some(format!(
                "--supersample {k} does not combine with --mode path: its jittered camera paths already \
                 integrate each pixel (raise --samples instead)"
            )),
            Some(Command::Render { supersample: Some(k), .. })
                if view.aa.is_some_and(|a| a != AaMode::None) =>
            {
                Some(format!(
                    "--aa has no effect with --supersample {k}: the {k}x{k} samples are the anti-aliasing \
                     (the large frame is filtered down, not post-filtered)"
                ))
            }
            _ => view.without_effect(name),
        };
        if let Some(p) = problem {
            // The subcommand's own usage line under the message.
            let mut cli = Cli::command();
            let sub = cli.find_subcommand_mut(name).expect("a defined subcommand");
            sub.set_bin_name(format!("hybrid-rt {name}"));
            sub.error(ErrorKind::ArgumentConflict, p).exit();
        }
    }
}

fn parse_vulkan_api(s: &str) -> Result<u32, String> {
    match s {
        "1.2" => Ok(ash::vk::API_VERSION_1_2),
        "1.3" => Ok(ash::vk::API_VERSION_1_3),
        _ => Err(format!("'{s}' is not 1.2 or 1.3")),
    }
}

fn run(cli: Cli) -> Result<()> {
    let env_validation = std::env::var("HYBRID_RT_VALIDATION").is_ok_and(|v| v != "0" && !v.is_empty());
    let mut gpu = GpuOptions {
        validation: cli.gpu.validation || cli.gpu.sync_validation || env_validation,
        sync_validation: cli.gpu.sync_validation,
        device: cli.gpu.device.parse::<DeviceSelector>().unwrap_or_default(),
        disable_ray_tracing: cli.gpu.no_rt,
        disable_ray_query: cli.gpu.no_ray_query,
        disable_trace_rays_indirect: false,
        max_api_version: cli.gpu.vulkan_api,
        capture_frame: None,
    };
    match cli.command {
        Some(Command::Info) => {
            print!("{}", app::info_command(&gpu)?);
            Ok(())
        }
        Some(Command::Render { view, out, hdr_out, strict, capture_frame, supersample, ss_filter }) => {
            gpu.capture_frame = capture_frame;
            let mut job = view.job()?;
            job.supersample =
                supersample.map(|factor| Supersample { factor, filter: ss_filter.unwrap_or_default() });
            app::render_command(&gpu, &job, &out, hdr_out.as_deref(), strict)
        }
        Some(Command::Bench {
            view,
            frames,
            warmup,
            compare_modes,
            compare_backends,
            accel_update,
            compare_accel_updates,
            csv,
            rays,
            ray_reps,
            ray_traversal,
            capture_frame,
        }) => {
            if rays {
                return app::rays_command(&gpu, &view.job()?, ray_reps, ray_traversal, view.backend);
            }
            gpu.capture_frame = capture_frame;
            let modes = if compare_modes { vec![Mode::Hybrid, Mode::Rt] } else { vec![view.mode] };
            let backends = if compare_backends {
                vec![Backend::Query, Backend::Pipeline, Backend::Compute]
            } else {
                vec![view.backend]
            };
            let updates = if compare_accel_updates {
                vec![AccelUpdate::Refit, AccelUpdate::Rebuild, AccelUpdate::Full]
            } else {
                vec![accel_update]
            };
            let mut variants = Vec::new();
            for &mode in &modes {
                for &backend in &backends {
                    for &accel in &updates {
                        variants.push(app::BenchVariant { mode, backend, accel });
                    }
                }
            }
            app::bench_command(&gpu, &view.job()?, frames, warmup, &variants, csv.as_deref())
        }
        Some(Command::Report {
            view,
            frames,
            warmup,
            knobs,
            ref_kind,
            ref_samples,
            ref_max_samples,
            ref_cache,
            no_ref_cache,
            attribution_samples,
            ref_max_depth,
            ref_min_weight,
            ref_backend,
            ref_mode,
            no_ray_counts,
            ref_supersample,
            ref_ss_filter,
            stability,
            cases,
            budget_paths,
            tone_sheet,
            prt,
            prt_sweep,
            out,
        }) => {
            if prt {
                let opts = report::prt::PrtReportOptions {
                    frames,
                    warmup,
                    knobs: report::prt::parse_selection(knobs.as_deref().unwrap_or("")).context("--knobs")?,
                    sweep: prt_sweep,
                    reference: hybrid_rt::render::ReferenceSettings {
                        samples: view.env.reference_samples.unwrap_or(report::prt::DEFAULT_REFERENCE.samples),
                        bounces: view.env.reference_bounces.unwrap_or(report::prt::DEFAULT_REFERENCE.bounces),
                    },
                    ..report::prt::PrtReportOptions::new(view.job()?, out)
                };
                return report::prt::command(&gpu, &opts);
            }
            if !budget_paths.is_empty() {
                let opts = report::budget_paths::BudgetPathOptions {
                    job: view.job()?,
                    out,
                    frames,
                    warmup,
                    shares: budget_paths,
                };
                return report::budget_paths::command(&gpu, &opts);
            }
            if !tone_sheet.is_empty() {
                let job = view.job()?;
                let files = app::with_context(&gpu, |ctx| {
                    report::tone_sheet::tone_sheets(ctx, &job, &tone_sheet, warmup, &out)
                })?;
                for f in files {
                    println!("wrote {}", f.display());
                }
                return Ok(());
            }
            if stability {
                let opts = report::stability::StabilityOptions {
                    frames,
                    warmup,
                    cases,
                    ..report::stability::StabilityOptions::new(view.job()?, out)
                };
                return report::stability::stability_command(&gpu, &opts);
            }
            let opts = ReportOptions {
                frames,
                warmup,
                knobs: report::knobs::parse_selection(knobs.as_deref().unwrap_or("")).context("--knobs")?,
                reference: ReferenceSettings {
                    max_depth: ref_max_depth,
                    min_weight: ref_min_weight,
                    backend: ref_backend,
                    mode: if ref_kind == RefKind::Path { Mode::Path } else { ref_mode },
                    samples: ref_samples,
                    max_samples: ref_max_samples.max(ref_samples),
                },
                truth_cache: match (no_ref_cache, ref_cache) {
                    (true, _) => None,
                    (false, Some(dir)) => Some(dir),
                    (false, None) => report::truth::default_cache_dir(),
                },
                count_rays: !no_ray_counts,
                attribution_samples,
                aa_reference: Supersample { factor: ref_supersample, filter: ref_ss_filter },
                ..ReportOptions::new(view.job()?, out)
            };
            report::report_command(&gpu, &opts)
        }
        Some(Command::Compare { a, b, out, threshold, exposure }) => {
            let c = report::compare::compare(&a, &b, out.as_deref(), threshold, exposure)?;
            print!("{}", c.summary());
            if let Some(o) = out {
                println!("wrote {}", o.display());
            }
            Ok(())
        }
        Some(Command::View { view, present_mode, frames, screenshot, test_resize, capture_frame }) => {
            if let (Some(c), Some(f)) = (capture_frame, frames) {
                if c >= f as u64 {
                    let mut cli = Cli::command();
                    let sub = cli.find_subcommand_mut("view").expect("a defined subcommand");
                    sub.set_bin_name("hybrid-rt view");
                    let msg = format!("--capture-frame {c}: the viewer presents only --frames {f} frames");
                    sub.error(ErrorKind::ValueValidation, msg).exit();
                }
            }
            gpu.capture_frame = capture_frame;
            let event_loop = viewer::open_display()?;
            let opts = ViewerOptions {
                gpu,
                job: view.job()?,
                present_mode,
                frames: frames.map(|f| f as u64),
                fixed_fps: view.fps,
                screenshot,
                test_resize,
            };
            viewer::run(event_loop, opts)
        }
        None => default_command(gpu),
    }
}

/// No command: the viewer on the default scene when a window can be opened,
/// else (or with HYBRID_RT_HEADLESS=1) the headless render to out/default.png.
fn default_command(gpu: GpuOptions) -> Result<()> {
    let job = RenderJob::new(app::default_scene_path()?, 1280, 720);
    let headless =
        |gpu: &GpuOptions| app::render_command(gpu, &job, &PathBuf::from("out/default.png"), None, false);
    if std::env::var("HYBRID_RT_HEADLESS").is_ok_and(|v| v != "0" && !v.is_empty()) {
        log::info!("HYBRID_RT_HEADLESS is set: rendering the default scene headless");
        return headless(&gpu);
    }
    let event_loop = match viewer::open_display() {
        Ok(el) => el,
        Err(why) => {
            log::info!("no viewer ({why}): rendering the default scene headless");
            return headless(&gpu);
        }
    };
    log::info!(
        "display available: opening the viewer (`hybrid-rt render` or HYBRID_RT_HEADLESS=1 for a file)"
    );
    let opts = ViewerOptions {
        gpu: gpu.clone(),
        job: job.clone(),
        present_mode: PresentMode::Fifo,
        frames: None,
        fixed_fps: None,
        screenshot: None,
        test_resize: false,
    };
    match viewer::run(event_loop, opts) {
        Err(e) if e.downcast_ref::<viewer::NoDisplay>().is_some() => {
            log::warn!("{e}: rendering the default scene headless instead");
            headless(&gpu)
        }
        r => r,
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    cli.check_usage();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or(&cli.gpu.log))
        .format_timestamp_millis()
        .init();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// What `report` measures against.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum RefKind {
    /// The path-traced ground truth.
    Path,
    /// The renderer itself at its deepest settings.
    #[value(name = "self")]
    Own,
}

fn parse_ref_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (4..=app::MAX_PATH_SAMPLES).contains(&v) => Ok(v),
        _ => {
            Err(format!("'{s}': expected a whole number of paths per pixel, 4 to {}", app::MAX_PATH_SAMPLES))
        }
    }
}

/// A switch on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum OnOff {
    On,
    Off,
}
