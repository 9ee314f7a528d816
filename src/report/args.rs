//! `report`'s command line: one subcommand per report (`knobs`, the
//! default, `stability`, `budget-paths`, `tone-sheet`, `prt`), each with
//! only its own options; the earlier flag spellings (`report --stability`,
//! ...) stay as aliases. Also the checks across options clap cannot state.

use std::path::PathBuf;

use anyhow::{Context as _, Result};
use clap::{Args, Subcommand};

use super::{ReferenceSettings, ReportOptions};
use crate::app::cli_parse::*;
use crate::app::{GpuOptions, ViewArgs, MAX_PATH_SAMPLES};
use crate::render::shading::{Backend, Mode};
use crate::render::supersample::{SampleFilter, Supersample};

// The subcommand's help is the doc comment on `Command::Report` (main.rs).
#[derive(Args, Clone)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct ReportArgs {
    #[command(subcommand)]
    kind: Option<ReportKind>,
    #[command(flatten)]
    common: Common,
    #[command(flatten)]
    knobs: KnobArgs,
    /// Same as `report stability` (the earlier spelling).
    #[arg(long, conflicts_with_all = ["knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts", "ref_supersample", "ref_ss_filter"])]
    stability: bool,
    /// With --stability: `report stability --cases`.
    #[arg(long, requires = "stability", value_delimiter = ',')]
    cases: Vec<String>,
    /// Same as `report budget-paths --shares` (the earlier spelling).
    #[arg(long, value_delimiter = ',', value_parser = parse_share, conflicts_with_all = ["stability", "knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts", "tone_sheet"])]
    budget_paths: Vec<f64>,
    /// Same as `report tone-sheet --maps` (the earlier spelling).
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["stability", "knobs", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "no_ray_counts"])]
    tone_sheet: Vec<PathBuf>,
    /// Same as `report prt` (the earlier spelling; --knobs then picks
    /// among bands, sh-samples, transfer).
    #[arg(long, conflicts_with_all = ["stability", "budget_paths", "tone_sheet", "ref_backend", "ref_max_depth", "ref_min_weight", "ref_mode", "ref_supersample", "ref_ss_filter"])]
    prt: bool,
    /// With --prt: `report prt --sweep`.
    #[arg(long, requires = "prt")]
    prt_sweep: bool,
}

/// What every report takes: the scene and settings, frame counts, output.
#[derive(Args, Clone)]
pub struct Common {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Timed frames per setting (>= 5), after the warm-up.
    #[arg(long, default_value_t = 10, value_parser = parse_count, allow_hyphen_values = true)]
    pub frames: usize,
    /// Unmeasured frames per setting before timing (>= 1; the first
    /// compiles the setting's pipelines).
    #[arg(long, default_value_t = 2, value_parser = parse_count, allow_hyphen_values = true)]
    pub warmup: usize,
    /// Output directory.
    // (An Option only so `report <subcommand>` can leave the parent's
    // unset: clap requires it wherever it parses.)
    #[arg(long, required = true)]
    pub out: Option<PathBuf>,
}

impl Common {
    /// The options by value, `--out` as clap ensured it.
    fn parts(self) -> (ViewArgs, usize, usize, PathBuf) {
        (self.view, self.frames, self.warmup, self.out.expect("clap requires --out"))
    }
}

/// The knob report's own options.
#[derive(Args, Clone)]
pub struct KnobArgs {
    /// Knobs to sweep, comma-separated, each optionally with its values
    /// after '=' separated by ':' (e.g. "max-depth=0:2:8,mode"); knobs:
    /// max-depth, min-weight, effects, ambient, mode, backend, aa, accel-update
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
    /// Do not count rays per frame (saves a frame per setting).
    #[arg(long)]
    pub no_ray_counts: bool,
    /// The aa knob's reference: the base settings with K×K samples per
    /// pixel (1..=16) [default: 16 or 8 where the large frame stays within
    /// 4096² samples, else 4].
    #[arg(long, value_parser = parse_supersample, allow_hyphen_values = true)]
    pub ref_supersample: Option<u32>,
    /// How the aa knob's reference weighs its samples.
    #[arg(long, value_enum, default_value_t = SampleFilter::Box)]
    pub ref_ss_filter: SampleFilter,
}

#[derive(Subcommand, Clone)]
pub enum ReportKind {
    /// Image error (ꟻLIP, PSNR) against GPU time for every quality knob
    /// (what `report` without a subcommand runs).
    Knobs {
        #[command(flatten)]
        common: Common,
        #[command(flatten)]
        knobs: KnobArgs,
    },
    /// Numerical stability: stiff and extreme variants of the scene (moved
    /// far from the origin, scaled, grazing and facing mirrors, IOR near 1,
    /// a 1e5 environment texel, ...) on every available backend, with
    /// pass/fail thresholds.
    Stability {
        #[command(flatten)]
        common: Common,
        /// Only these cases (comma-separated; the canonicals they are
        /// compared with are added), e.g. "translate-1e3,ior-1.0".
        #[arg(long, value_delimiter = ',')]
        cases: Vec<String>,
    },
    /// The ray-tracing budget along the scene's camera path: paper mode,
    /// effects mode and effects mode with the raster fallback at each
    /// share, --frames points along the path after --warmup frames at its
    /// start; frame ms, heuristic share and ꟻLIP/PSNR against full effects
    /// per run, table + plot.
    BudgetPaths {
        #[command(flatten)]
        common: Common,
        /// Shares of the cost of tracing everything, comma-separated in [0, 1].
        #[arg(long, required = true, value_delimiter = ',', value_parser = parse_share)]
        shares: Vec<f64>,
    },
    /// Tone operators side by side: a contact sheet per map, the scene lit
    /// by each; rows operators, columns key values (log-average auto
    /// exposure) and the fixed --exposure; tone_sheet.md with the measured
    /// exposures and pass ms.
    ToneSheet {
        #[command(flatten)]
        common: Common,
        /// Radiance .hdr maps, comma-separated.
        #[arg(long, required = true, value_delimiter = ',')]
        maps: Vec<PathBuf>,
    },
    /// The environment light's ambient (SH irradiance and diffuse PRT)
    /// against a ray-traced reference of the view (--reference-samples N
    /// (1024) --reference-bounces K (3 here)).
    Prt {
        #[command(flatten)]
        common: Common,
        /// Knobs, comma-separated, each optionally with its values after
        /// '=' separated by ':': bands, sh-samples, transfer; their product
        /// runs [default: all].
        #[arg(long)]
        knobs: Option<String>,
        /// One knob at a time around the base settings instead of the product.
        #[arg(long)]
        sweep: bool,
    },
}

impl ReportArgs {
    /// The report these options run: the subcommand, else the one an
    /// earlier flag names, else the knobs.
    pub fn kind(self) -> ReportKind {
        let ReportArgs { kind, common, knobs, stability, cases, budget_paths, tone_sheet, prt, prt_sweep } =
            self;
        match kind {
            Some(k) => k,
            None if prt => ReportKind::Prt { common, knobs: knobs.knobs, sweep: prt_sweep },
            None if !budget_paths.is_empty() => ReportKind::BudgetPaths { common, shares: budget_paths },
            None if !tone_sheet.is_empty() => ReportKind::ToneSheet { common, maps: tone_sheet },
            None if stability => ReportKind::Stability { common, cases },
            None => ReportKind::Knobs { common, knobs },
        }
    }

    /// Checks across options clap cannot state: a usage error's message.
    pub fn usage_problem(&self) -> Option<String> {
        self.clone().kind().usage_problem()
    }

    /// The options every report shares.
    pub fn common(&self) -> &Common {
        match &self.kind {
            Some(k) => k.common(),
            None => &self.common,
        }
    }
}

impl ReportKind {
    /// The subcommand's name.
    pub fn name(&self) -> &'static str {
        match self {
            ReportKind::Knobs { .. } => "knobs",
            ReportKind::Stability { .. } => "stability",
            ReportKind::BudgetPaths { .. } => "budget-paths",
            ReportKind::ToneSheet { .. } => "tone-sheet",
            ReportKind::Prt { .. } => "prt",
        }
    }

    pub fn common(&self) -> &Common {
        match self {
            ReportKind::Knobs { common, .. }
            | ReportKind::Stability { common, .. }
            | ReportKind::BudgetPaths { common, .. }
            | ReportKind::ToneSheet { common, .. }
            | ReportKind::Prt { common, .. } => common,
        }
    }

    /// Checks across options clap cannot state: a usage error's message.
    pub fn usage_problem(&self) -> Option<String> {
        let view = &self.common().view;
        let reference_rule = "--reference-samples is a report option only of `report prt` (the ambient's \
                              reference): report renders one frame per variant, and the reference needs \
                              ceil(N/4) (render it with `render --reference-samples N`, then `compare`)";
        let problem = match self {
            ReportKind::Knobs { common, knobs } => knobs.usage_problem(common),
            ReportKind::Stability { .. } | ReportKind::ToneSheet { .. } if view.fps.is_some() => {
                Some(FPS_RULE.into())
            }
            ReportKind::Prt { knobs: Some(k), .. } if super::prt::parse_selection(k).is_err() => {
                super::prt::parse_selection(k).err().map(|e| format!("--knobs: {e:#}"))
            }
            ReportKind::Prt { knobs: Some(_), .. } if view.fps.is_some() => Some(FPS_RULE.into()),
            ReportKind::Prt { common, .. } if common.frames < 5 => Some(few_frames(common.frames)),
            _ => None,
        };
        let problem = problem.or_else(|| match self {
            ReportKind::Prt { .. } => None,
            _ if view.env.reference_samples.is_some() => Some(reference_rule.into()),
            _ => None,
        });
        problem.or_else(|| view.without_effect("report"))
    }

    /// Runs the report.
    pub fn run(self, gpu: &GpuOptions) -> Result<()> {
        match self {
            ReportKind::Knobs { common, knobs } => knobs.run(gpu, common),
            ReportKind::Prt { common, knobs, sweep } => {
                let (view, frames, warmup, out) = common.parts();
                let opts = super::prt::PrtReportOptions {
                    frames,
                    warmup,
                    knobs: super::prt::parse_selection(knobs.as_deref().unwrap_or("")).context("--knobs")?,
                    sweep,
                    reference: crate::render::ReferenceSettings {
                        samples: view.env.reference_samples.unwrap_or(super::prt::DEFAULT_REFERENCE.samples),
                        bounces: view.env.reference_bounces.unwrap_or(super::prt::DEFAULT_REFERENCE.bounces),
                    },
                    ..super::prt::PrtReportOptions::new(view.job()?, out)
                };
                super::prt::command(gpu, &opts)
            }
            ReportKind::BudgetPaths { common, shares } => {
                let (view, frames, warmup, out) = common.parts();
                let opts =
                    super::budget_paths::BudgetPathOptions { job: view.job()?, out, frames, warmup, shares };
                super::budget_paths::command(gpu, &opts)
            }
            ReportKind::ToneSheet { common, maps } => {
                let (view, _, warmup, out) = common.parts();
                let job = view.job()?;
                let files = crate::app::with_context(gpu, |ctx| {
                    super::tone_sheet::tone_sheets(ctx, &job, &maps, warmup, &out)
                })?;
                for f in files {
                    println!("wrote {}", f.display());
                }
                Ok(())
            }
            ReportKind::Stability { common, cases } => {
                let (view, frames, warmup, out) = common.parts();
                let opts = super::stability::StabilityOptions {
                    frames,
                    warmup,
                    cases,
                    ..super::stability::StabilityOptions::new(view.job()?, out)
                };
                super::stability::stability_command(gpu, &opts)
            }
        }
    }
}

impl KnobArgs {
    fn usage_problem(&self, common: &Common) -> Option<String> {
        if self.ref_kind == RefKind::Own && self.attribution_samples != 256 {
            return Some(
                "--attribution-samples measures against the path-traced truth: leave out --ref self".into(),
            );
        }
        if self.ref_kind == RefKind::Path
            && (self.ref_mode != Mode::Rt || self.ref_max_depth != 16 || self.ref_min_weight != 0.001)
        {
            return Some(
                "--ref-mode, --ref-max-depth and --ref-min-weight set the self reference: add --ref self \
                 (the default reference is the path-traced truth)"
                    .into(),
            );
        }
        if common.view.fps.is_some() && self.knobs.as_deref().is_some_and(|k| !k.contains("accel-update")) {
            return Some(FPS_RULE.into());
        }
        if let Some(Err(e)) = self.knobs.as_deref().map(super::knobs::parse_selection) {
            return Some(format!("--knobs: {e:#}"));
        }
        if common.frames < 5 {
            return Some(few_frames(common.frames));
        }
        None
    }

    fn run(self, gpu: &GpuOptions, common: Common) -> Result<()> {
        let KnobArgs {
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
        } = self;
        let (view, frames, warmup, out) = common.parts();
        let job = view.job()?;
        let factor =
            ref_supersample.unwrap_or(crate::render::supersample::reference_factor(job.width, job.height));
        let opts = ReportOptions {
            frames,
            warmup,
            knobs: super::knobs::parse_selection(knobs.as_deref().unwrap_or("")).context("--knobs")?,
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
                (false, None) => super::truth::default_cache_dir(),
            },
            count_rays: !no_ray_counts,
            attribution_samples,
            aa_reference: Supersample { factor, filter: ref_ss_filter },
            ..ReportOptions::new(job, out)
        };
        super::report_command(gpu, &opts)
    }
}

/// `--fps` outside the one place it steps frames.
const FPS_RULE: &str = "--fps has no effect here: report renders still frames at --time; it steps only the \
                        accel-update knob's frames";

/// A timed report with too few frames for its p95.
fn few_frames(frames: usize) -> String {
    format!("--frames {frames} is too few for a p95; use at least 5")
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
