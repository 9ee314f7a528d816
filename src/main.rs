//! Command line: `info`, `render`, `bench`, `report`, `compare`, `view`. With no command it opens the
//! viewer on the bundled default scene when a display is available, else renders it to `out/default.png`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{error::ErrorKind, CommandFactory, Parser, Subcommand};

use hybrid_rt::app::cli_parse::*;
use hybrid_rt::app::{self, AccelUpdate, GpuArgs, GpuOptions, RenderJob, ViewArgs};
use hybrid_rt::render::rays::Traversal;
use hybrid_rt::render::shading::{AaMode, Backend, Mode};
use hybrid_rt::render::supersample::{SampleFilter, Supersample};
use hybrid_rt::report::{self, ReportArgs};
use hybrid_rt::viewer::{self, PresentMode, ViewerOptions};

#[derive(Parser)]
#[command(name = "hybrid-rt", version, about = "Hybrid rasterization + ray-tracing renderer (Vulkan)")]
struct Cli {
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(subcommand)]
    command: Option<Command>,
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
        /// Cost against size: generated scenes of 1e4 to 1e7 unique triangles and of 1 to
        /// 1e6 instances of one mesh, each size and backend in its own process (load stages,
        /// per-pass frame ms, peak RSS, GPU memory by category, bytes per triangle); prints a
        /// table, writes scale.csv and log-log plots to --scale-out. Backends: --backend, else
        /// compute and (where offered) query. Other settings (size, effects, budget) apply.
        #[arg(long, conflicts_with_all = ["rays", "compare_modes", "compare_backends", "compare_accel_updates", "csv", "capture_frame", "scene"])]
        scale: bool,
        /// With --scale: the unique series' largest size (0 skips the series).
        #[arg(long, default_value_t = 10_000_000, requires = "scale")]
        scale_max_triangles: u64,
        /// With --scale: the instanced series' largest count (0 skips the series).
        #[arg(long, default_value_t = 1_000_000, requires = "scale")]
        scale_max_instances: u64,
        /// With --scale: measured frames per size (after the first and two unmeasured).
        #[arg(long, default_value_t = 3, value_parser = parse_count, allow_hyphen_values = true)]
        scale_frames: usize,
        /// With --scale: the folder for scale.csv and the plots.
        #[arg(long, default_value = "out/scale", requires = "scale")]
        scale_out: PathBuf,
        /// The BVH builders side by side on generated scenes (comma-separated unique:N or
        /// instanced:N): host binned SAH, host split BVH (up to its size limit), host LBVH and
        /// the device LBVH (GPU ms per step); build ms, Mtri/s and SAH cost of each tree.
        #[arg(long, value_delimiter = ',', value_name = "SCENES", conflicts_with_all = ["rays", "compare_modes", "compare_backends", "compare_accel_updates", "csv", "capture_frame", "scene", "scale"])]
        builders: Vec<report::scale::Point>,
        /// One size of --scale, measured in this process (what --scale runs per size).
        #[arg(long, hide = true, conflicts_with = "scale")]
        scale_point: Option<report::scale::Point>,
        /// Capture frame N (0-based, in the order rendered: per variant the ray-counting
        /// frame and the warm-up, then the measured frames) with RenderDoc's in-application API
        /// (under `renderdoccmd capture`, or with librenderdoc.so loadable);
        /// the log names the capture file.
        #[arg(long, value_name = "N")]
        capture_frame: Option<u64>,
    },
    /// Image error (ꟻLIP, PSNR) against GPU time for every quality knob:
    /// report.md, report.csv, error_vs_time.png and error maps in --out.
    Report(Box<ReportArgs>),
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

impl Cli {
    /// Checks across options the parser cannot express; exits like a clap
    /// usage error (code 2).
    fn check_usage(&self) {
        let (name, view) = match &self.command {
            Some(Command::Render { view, .. }) => ("render", view),
            Some(Command::Bench { view, .. }) => ("bench", view),
            Some(Command::Report(args)) => ("report", &args.common().view),
            Some(Command::View { view, .. }) => ("view", view),
            Some(Command::Info) | Some(Command::Compare { .. }) | None => return,
        };
        let problem = match &self.command {
            Some(Command::Report(args)) => args.usage_problem(),
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

fn run(cli: Cli) -> Result<()> {
    let mut gpu = cli.gpu.options();
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
            scale,
            scale_max_triangles,
            scale_max_instances,
            scale_frames,
            scale_out,
            scale_point,
            builders,
            capture_frame,
        }) => {
            if !builders.is_empty() {
                return report::builders::builders_command(&gpu, &builders);
            }
            if let Some(point) = scale_point {
                let job = RenderJob {
                    settings: view.job()?.settings,
                    ..RenderJob::new("", view.width, view.height)
                };
                return report::scale::measure_point(&gpu, point, &job, scale_frames);
            }
            if scale {
                let backends = match view.backend {
                    Backend::Auto => {
                        app::offered_backends(&gpu)?.into_iter().filter(|b| *b != Backend::Pipeline).collect()
                    }
                    b => vec![b],
                };
                let opts = report::scale::ScaleOptions {
                    max_triangles: scale_max_triangles,
                    max_instances: scale_max_instances,
                    out: scale_out,
                    backends,
                };
                return report::scale::scale_command(&opts).map(|_| ());
            }
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
        Some(Command::Report(args)) => args.kind().run(&gpu),
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
