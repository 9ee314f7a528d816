//! `report`'s command line: its options, the checks across them clap
//! cannot state, and which report they run.

use std::path::PathBuf;

use anyhow::{Context as _, Result};
use clap::Args;

use super::{ReferenceSettings, ReportOptions};
use crate::app::cli_parse::*;
use crate::app::{GpuOptions, ViewArgs, MAX_PATH_SAMPLES};
use crate::render::shading::{Backend, Mode};
use crate::render::supersample::{SampleFilter, Supersample};

// Image error (ꟻLIP, PSNR) against GPU time for every quality knob, or
// one of the other reports (--stability, --budget-paths, --tone-sheet, --prt);
// the subcommand's help is the doc comment on `Command::Report` (main.rs).
#[derive(Args)]
pub struct ReportArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Timed frames per setting (>= 5), after the warm-up.
    #[arg(long, default_value_t = 10, value_parser = parse_count, allow_hyphen_values = true)]
    pub frames: usize,
    /// Unmeasured frames per setting before timing (>= 1; the first
    /// compiles the setting's pipelines).
    #[arg(long, default_value_t = 2, value_parser = parse_count, allow_hyphen_values = true)]
    pub warmup: usize,
    /// Knobs to sweep, comma-separated, each optionally with its values
    /// after '=' separated by ':' (e.g. "max-depth=0:2:8,mode"); knobs:
    /// max-depth, min-weight, effects, mode, backend, aa, accel-update
    /// (animated scenes: with --animation, frames --fps apart), budget
    /// (share of the cost of tracing everything), resolution-scale.
    /// Default: all, with their full value lists.
    #[arg(long)]
    pub knobs: Option<String>,
    /// What every knob is measured against: path (the path-traced ground
    /// truth, --ref-samples, cached on disk) or self (this renderer at
    /// its deepest settings: --ref-mode, --ref-max-depth, --ref-min-weight).
    #[arg(long = "ref", value_enum, default_value_t = RefKind::Path)]
    pub ref_kind: RefKind,
    /// --ref path: paths per pixel to start with (doubled while the
    /// reference's own noise is over half the smallest error).
    #[arg(long, default_value_t = 256, value_parser = parse_ref_samples, allow_hyphen_values = true)]
    pub ref_samples: u32,
    /// --ref path: the most paths per pixel it may double to.
    #[arg(long, default_value_t = 4096, value_parser = parse_ref_samples, allow_hyphen_values = true)]
    pub ref_max_samples: u32,
    /// --ref path: cache directory [default: $HYBRID_RT_TRUTH_CACHE, else
    /// $XDG_CACHE_HOME/hybrid-rt/truth, else ~/.cache/hybrid-rt/truth].
    #[arg(long, value_name = "DIR", conflicts_with = "no_ref_cache")]
    pub ref_cache: Option<PathBuf>,
    /// --ref path: render the reference even if a cached one exists, and cache nothing.
    #[arg(long)]
    pub no_ref_cache: bool,
    /// --ref path: samples per pixel of each term of the default frame's
    /// error attribution (0 leaves it out).
    #[arg(long, default_value_t = 256)]
    pub attribution_samples: u32,
    /// --ref self: maximum recursion depth (pure-RT mode, every effect).
    #[arg(long, default_value_t = 16, value_parser = parse_max_depth, allow_hyphen_values = true)]
    pub ref_max_depth: u32,
    /// --ref self: importance cutoff in [0, 1].
    #[arg(long, default_value_t = 0.001, value_parser = parse_min_weight, allow_hyphen_values = true)]
    pub ref_min_weight: f32,
    /// Reference: ray backend [default: the --backend of the base settings].
    #[arg(long, value_enum)]
    pub ref_backend: Option<Backend>,
    /// --ref self: rt (camera rays traced) or hybrid (then the rows leave
    /// out the hybrid-vs-rt difference the self-check reports).
    #[arg(long, value_enum, default_value_t = Mode::Rt)]
    pub ref_mode: Mode,
    /// Do not count rays per frame (saves a pipeline compile per setting).
    #[arg(long)]
    pub no_ray_counts: bool,
    /// The aa knob's reference: the base settings with K×K samples per
    /// pixel (1..=16).
    #[arg(long, default_value_t = 4, value_parser = parse_supersample, allow_hyphen_values = true)]
    pub ref_supersample: u32,
    /// How the aa knob's reference weighs its samples.
    #[arg(long, value_enum, default_value_t = SampleFilter::Box)]
    pub ref_ss_filter: SampleFilter,
    /// Numerical-stability report instead: stiff and extreme variants
    /// of the scene (moved far from the origin, scaled, grazing and
    /// facing mirrors, IOR near 1, a 1e5 environment texel, ...) on
    /// every available backend, with pass/fail thresholds.
    #[arg(long, conflicts_with_all = ["knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts", "ref_supersample", "ref_ss_filter"])]
    pub stability: bool,
    /// With --stability: only these cases (comma-separated; the
    /// canonicals they are compared with are added), e.g.
    /// "translate-1e3,ior-1.0".
    #[arg(long, requires = "stability", value_delimiter = ',')]
    pub cases: Vec<String>,
    /// The ray-tracing budget along the scene's camera path instead:
    /// paper mode, effects mode and effects mode with the raster
    /// fallback at these shares of the cost of tracing
    /// everything (comma-separated in [0, 1]), --frames points along
    /// the path after --warmup frames at its start; frame ms, heuristic
    /// share and ꟻLIP/PSNR against full effects per run, table + plot.
    #[arg(long, value_delimiter = ',', value_parser = parse_share, conflicts_with_all = ["stability", "knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts", "tone_sheet"])]
    pub budget_paths: Vec<f64>,
    /// Tone operators side by side instead: a contact sheet per Radiance
    /// .hdr map (comma-separated), the scene lit by each; rows operators,
    /// columns key values (log-average auto exposure) and the fixed
    /// --exposure; tone_sheet.md with the measured exposures and pass ms.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["stability", "knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts"])]
    pub tone_sheet: Vec<PathBuf>,
    /// The environment light's ambient instead (SH irradiance and
    /// diffuse PRT) against a ray-traced reference of the view
    /// (--reference-samples N (1024) --reference-bounces K (3 here)); --knobs
    /// picks among bands, sh-samples, transfer, whose product runs.
    #[arg(long, conflicts_with_all = ["stability", "budget_paths", "tone_sheet", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "ref_supersample", "ref_ss_filter"])]
    pub prt: bool,
    /// With --prt: one knob at a time around the base settings instead
    /// of the product.
    #[arg(long, requires = "prt")]
    pub prt_sweep: bool,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

impl ReportArgs {
    /// Checks across options clap cannot state: a usage error's message.
    pub fn usage_problem(&self) -> Option<String> {
        match self {
        Self { ref_kind: RefKind::Own, attribution_samples, .. } if *attribution_samples != 256 => {
            Some("--attribution-samples measures against the path-traced truth: leave out --ref self".into())
        }
        Self { ref_kind: RefKind::Path, ref_mode, ref_max_depth, ref_min_weight, .. }
            if *ref_mode != Mode::Rt || *ref_max_depth != 16 || *ref_min_weight != 0.001 =>
        {
            Some(
                "--ref-mode, --ref-max-depth and --ref-min-weight set the self reference: add --ref self \
                 (the default reference is the path-traced truth)"
                    .into(),
            )
        }
        Self { knobs, stability, tone_sheet, .. }
            if self.view.fps.is_some()
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
        Self { knobs: Some(k), prt: false, stability: false, tone_sheet, budget_paths, .. }
            if tone_sheet.is_empty() && budget_paths.is_empty() && super::knobs::parse_selection(k).is_err() =>
        {
            let e = super::knobs::parse_selection(k).expect_err("checked above");
            Some(format!("--knobs: {e:#}"))
        }
        Self { frames, stability: false, tone_sheet, budget_paths, .. }
            if *frames < 5 && tone_sheet.is_empty() && budget_paths.is_empty() =>
        {
            Some(format!("--frames {frames} is too few for a p95; use at least 5"))
        }
        Self { prt: false, .. } if self.view.env.reference_samples.is_some() => Some(
            "--reference-samples is a report option only with --prt (the ambient's reference): report \
             renders one frame per variant, and the reference needs ceil(N/4) (render it with `render \
             --reference-samples N`, then `compare`)"
                .into(),
        ),
            _ => self.view.without_effect("report"),
        }
    }

    /// Runs the report the options pick.
    pub fn run(self, gpu: &GpuOptions) -> Result<()> {
        let ReportArgs {
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
        } = self;
        if prt {
            let opts = crate::report::prt::PrtReportOptions {
                frames,
                warmup,
                knobs: crate::report::prt::parse_selection(knobs.as_deref().unwrap_or(""))
                    .context("--knobs")?,
                sweep: prt_sweep,
                reference: crate::render::ReferenceSettings {
                    samples: view
                        .env
                        .reference_samples
                        .unwrap_or(crate::report::prt::DEFAULT_REFERENCE.samples),
                    bounces: view
                        .env
                        .reference_bounces
                        .unwrap_or(crate::report::prt::DEFAULT_REFERENCE.bounces),
                },
                ..crate::report::prt::PrtReportOptions::new(view.job()?, out)
            };
            return crate::report::prt::command(gpu, &opts);
        }
        if !budget_paths.is_empty() {
            let opts = crate::report::budget_paths::BudgetPathOptions {
                job: view.job()?,
                out,
                frames,
                warmup,
                shares: budget_paths,
            };
            return crate::report::budget_paths::command(gpu, &opts);
        }
        if !tone_sheet.is_empty() {
            let job = view.job()?;
            let files = crate::app::with_context(gpu, |ctx| {
                crate::report::tone_sheet::tone_sheets(ctx, &job, &tone_sheet, warmup, &out)
            })?;
            for f in files {
                println!("wrote {}", f.display());
            }
            return Ok(());
        }
        if stability {
            let opts = crate::report::stability::StabilityOptions {
                frames,
                warmup,
                cases,
                ..crate::report::stability::StabilityOptions::new(view.job()?, out)
            };
            return crate::report::stability::stability_command(gpu, &opts);
        }
        let opts = ReportOptions {
            frames,
            warmup,
            knobs: crate::report::knobs::parse_selection(knobs.as_deref().unwrap_or(""))
                .context("--knobs")?,
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
                (false, None) => crate::report::truth::default_cache_dir(),
            },
            count_rays: !no_ray_counts,
            attribution_samples,
            aa_reference: Supersample { factor: ref_supersample, filter: ref_ss_filter },
            ..ReportOptions::new(view.job()?, out)
        };
        crate::report::report_command(gpu, &opts)
    }
}

/// What `report` measures against.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RefKind {
    /// The path-traced ground truth.
    Path,
    /// The renderer itself at its deepest settings.
    #[value(name = "self")]
    Own,
}

pub fn parse_ref_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (4..=MAX_PATH_SAMPLES).contains(&v) => Ok(v),
        _ => Err(format!("'{s}': expected a whole number of paths per pixel, 4 to {}", MAX_PATH_SAMPLES)),
    }
}
