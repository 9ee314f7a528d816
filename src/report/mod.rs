//! `report`: image error against run time for every quality knob. One process renders the reference,
//! then every value of every selected knob (warmed up, timed) and compares each with it. Writes
//! `report.md`, `report.csv`, `error_vs_time.png` and an error map per knob (its worst setting).
//! See README "Report".
//!
//! Modules: `metrics` (ꟻLIP, PSNR, relMSE), `knobs`, `measure` (warm-up, GPU timing), `write`
//! (tables), `plot` (chart, Pareto front), `compare` (two image files), `stability` (`report
//! stability`), `tone_sheet` (`report tone-sheet`), `prt` and `prt_write` (`report prt`).

pub mod args;
pub mod attribution;
pub mod budget_paths;
pub mod builders;
pub mod compare;
pub mod knobs;
pub mod measure;
pub mod metrics;
pub mod plot;
pub mod prt;
pub mod prt_write;
pub mod scale;
pub mod stability;
pub mod tone_sheet;
pub mod truth;
pub mod write;
pub use args::ReportArgs;

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};

use crate::app::{load_posed, resolve_shading, with_context, GpuOptions, RenderJob};
use crate::render::budget::{BudgetSettings, Fallback};
use crate::render::shading::{Backend, Mode};
use crate::render::supersample::{render_supersampled, SampleFilter, Supersample};
use crate::render::{RenderSettings, Renderer};
use crate::vk::Context;
use knobs::{KnobSelection, Variant};
use measure::Measured;
use metrics::{Errors, FlipMap, LdrImage};

/// The reference's settings: by default the path-traced truth (report/truth.rs), at least `samples`
/// paths per pixel, doubled up to `max_samples` until its noise is under half the smallest error.
/// `--ref self`: the renderer in pure-RT (or hybrid) mode with every effect, `max_depth`, `min_weight`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceSettings {
    pub max_depth: u32,
    pub min_weight: f32,
    /// None: the base settings' backend.
    pub backend: Option<Backend>,
    /// Path: the ground truth. Rt (camera rays) or Hybrid: the self
    /// reference; Hybrid measures the other knobs without the
    /// hybrid-vs-rt difference (the self-check) in every row.
    pub mode: Mode,
    pub samples: u32,
    pub max_samples: u32,
}

impl ReferenceSettings {
    /// `--ref self`: converged on the bundled scenes at a bounded cost (the
    /// weight cutoff keeps dielectric branching, 2^depth without it, affordable).
    pub const SELF: ReferenceSettings = ReferenceSettings {
        max_depth: 16,
        min_weight: 0.001,
        backend: None,
        mode: Mode::Rt,
        samples: 256,
        max_samples: 4096,
    };
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings { mode: Mode::Path, ..Self::SELF }
    }
}

#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// Scene, camera, size and the base settings every knob changes one thing of.
    pub job: RenderJob,
    /// Timed frames per setting (>= 5).
    pub frames: usize,
    /// Unmeasured frames before them (>= 1; the first compiles pipelines).
    pub warmup: usize,
    pub knobs: Vec<KnobSelection>,
    pub reference: ReferenceSettings,
    /// Count rays by kind in one extra frame per setting (a frame uniform:
    /// no extra pipeline).
    pub count_rays: bool,
    /// The `aa` knob's reference: the base settings supersampled like this.
    pub aa_reference: Supersample,
    /// Where path-traced references are cached (None: not cached).
    pub truth_cache: Option<PathBuf>,
    /// Samples per pixel of each attribution term against the path-traced
    /// truth (report/attribution.rs); 0: no attribution.
    pub attribution_samples: u32,
    pub out: PathBuf,
}

impl ReportOptions {
    pub fn new(job: RenderJob, out: impl Into<PathBuf>) -> ReportOptions {
        let factor = crate::render::supersample::reference_factor(job.width, job.height);
        ReportOptions {
            job,
            frames: 10,
            warmup: 2,
            knobs: knobs::parse_selection("").expect("every knob"),
            reference: ReferenceSettings::default(),
            count_rays: true,
            aa_reference: Supersample { factor, filter: SampleFilter::Box },
            truth_cache: None,
            attribution_samples: 256,
            out: out.into(),
        }
    }

    /// The reference variant.
    pub fn reference_variant(&self) -> Variant {
        let base = self.job.settings;
        let mut effects = base.effects;
        (effects.shadows, effects.reflections, effects.refractions) = (true, true, true);
        effects.max_depth = self.reference.max_depth;
        effects.min_weight = self.reference.min_weight;
        let settings = RenderSettings {
            mode: self.reference.mode,
            effects,
            backend: self.reference.backend.unwrap_or(base.backend),
            path: crate::render::PathSettings { samples: self.reference.samples, ..Default::default() },
            ..base
        };
        let settings = match settings.mode {
            // No G-buffer: no debug view, no anti-aliasing, no budget.
            Mode::Path => RenderSettings {
                aa: crate::render::shading::AaMode::None,
                budget: None,
                reference: None,
                ..settings
            },
            _ => settings,
        };
        Variant::new(settings)
    }

    /// A cheaper reference (half the depth, ten times the weight cutoff):
    /// its distance to the reference shows how converged the reference is.
    fn convergence_variant(&self) -> Variant {
        let mut v = self.reference_variant();
        let e = &mut v.settings.effects;
        e.max_depth = (e.max_depth / 2).max(1);
        e.min_weight = if e.min_weight > 0.0 { (e.min_weight * 10.0).min(1.0) } else { 0.001 };
        v
    }
}

/// One setting of one knob, compared with the reference.
pub struct Row {
    pub knob: &'static str,
    pub value: String,
    /// Index into `Report::measured`.
    pub measured: usize,
    pub flip_mean: f64,
    pub psnr: f64,
    pub rel_mse: f64,
    pub map: FlipMap,
}

/// Two settings' distance to each other (the self-check, the convergence).
pub struct Distance {
    pub about: String,
    pub flip_mean: f64,
    pub psnr: f64,
    pub ldr: metrics::LdrDiff,
}

pub struct Report {
    pub scene: PathBuf,
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub warmup: usize,
    /// Every distinct setting rendered; the reference first.
    pub measured: Vec<Measured>,
    /// Index into `measured` of the base settings (in hybrid mode: every
    /// knob's row for its base value).
    pub base: usize,
    pub reference_exposure: f32,
    pub reference_settings: ReferenceSettings,
    /// Hybrid against pure RT at the base settings.
    pub self_check: Distance,
    /// The reference against a cheaper one (path-traced: its two halves).
    pub convergence: Distance,
    /// How the path-traced reference was made (None: the self reference).
    pub truth: Option<truth::Truth>,
    pub rows: Vec<Row>,
    /// Knob values not measured, with why.
    pub skipped: Vec<String>,
    /// What the `aa` knob's rows were compared with, when it ran.
    pub aa_reference: Option<AaReference>,
    /// The base frame's error per object and per missing term (path-traced
    /// truth, `attribution_samples` > 0).
    pub attribution: Option<attribution::Attribution>,
}

/// The `aa` knob's reference: AA changes only the final 8-bit image, so its rows are compared on
/// 8-bit images with the base settings K×K supersampled at the frozen base exposure, not with the
/// report's reference, whose radiance differences would drown the edges.
pub struct AaReference {
    pub supersample: Supersample,
    pub ldr: LdrImage,
    /// GPU ms of the large frame (sum of its passes).
    pub ms: f64,
}

impl Report {
    pub fn reference(&self) -> &Measured {
        &self.measured[0]
    }

    /// The row with the largest ꟻLIP of each knob, in knob order.
    pub fn worst_rows(&self) -> Vec<&Row> {
        let mut worst: Vec<&Row> = Vec::new();
        for r in &self.rows {
            match worst.iter_mut().find(|w| w.knob == r.knob) {
                Some(w) if r.flip_mean > w.flip_mean => *w = r,
                Some(_) => {}
                None => worst.push(r),
            }
        }
        worst
    }
}

/// The renderers of a run, one per frame size, destroyed together.
struct Renderers(Vec<Renderer>);

impl Renderers {
    fn get(&mut self, ctx: &Context, scene: &crate::scene::Scene, w: u32, h: u32) -> Result<&mut Renderer> {
        let extent = ash::vk::Extent2D { width: w, height: h };
        match self.0.iter().position(|r| r.extent() == extent) {
            Some(i) => Ok(&mut self.0[i]),
            None => {
                self.0.push(Renderer::new(ctx, scene, extent)?);
                Ok(self.0.last_mut().expect("just pushed"))
            }
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        for mut r in self.0.drain(..) {
            r.destroy(ctx);
        }
    }
}

/// The paper-mode cost of tracing every visible object of the view with
/// `settings` (one frame under an unlimited budget, with `renderer`).
fn budget_cost_of_everything(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &crate::scene::Scene,
    camera: &crate::scene::Camera,
    settings: &RenderSettings,
) -> Result<f64> {
    let settings = RenderSettings { budget: Some(BudgetSettings::paper(f64::INFINITY)), ..*settings };
    renderer.render(ctx, scene, camera, &settings)?;
    let spent = renderer.budget_report().map(|b| b.selection.spent);
    spent.context("report: the budget knob: no budget report (nothing is traced with the base settings?)")
}

/// Runs the report's renders and comparisons (writes nothing).
pub fn run(ctx: &Context, opts: &ReportOptions) -> Result<Report> {
    if opts.frames < 5 {
        bail!("report: --frames {} is too few for a p95; use at least 5", opts.frames);
    }
    let (width, height) = (opts.job.width, opts.job.height);
    let _ = opts.job.extent()?;
    let (scene, animation) = load_posed(&opts.job)?;
    let camera = opts.job.camera.resolve(&scene)?;
    let base = Variant::new(opts.job.settings);
    // `auto` resolved to the backend it picks, so equal frames dedupe.
    let concrete = |mut v: Variant| -> Result<Variant> {
        if let Some(b) = resolve_shading(ctx, &scene, &v.settings)?.backend {
            v.settings.backend = b;
        }
        Ok(v)
    };
    let reference = concrete(opts.reference_variant()).context("the reference settings cannot run")?;

    // Every setting, deduplicated: the reference first, then the checks,
    // then each knob's values.
    let mut variants: Vec<(Variant, String)> = Vec::new();
    let index_of = |variants: &mut Vec<(Variant, String)>, v: Variant, label: String| -> usize {
        match variants.iter().position(|(x, _)| *x == v) {
            Some(i) => i,
            None => {
                variants.push((v, label));
                variants.len() - 1
            }
        }
    };
    let truth_mode = reference.settings.mode == Mode::Path;
    index_of(&mut variants, reference, "reference".into());
    // The path-traced reference measures its convergence itself (halves).
    let convergence = match truth_mode {
        true => None,
        false => {
            Some(index_of(&mut variants, concrete(opts.convergence_variant())?, "convergence check".into()))
        }
    };
    let with_mode =
        |m: Mode| concrete(Variant { settings: RenderSettings { mode: m, ..base.settings }, ..base });
    let hybrid = with_mode(Mode::Hybrid).context("the base settings cannot run")?;
    let hybrid = index_of(&mut variants, hybrid, "self-check hybrid".into());
    let rt = with_mode(Mode::Rt).context("the base settings cannot run in rt mode")?;
    let rt = index_of(&mut variants, rt, "self-check rt".into());
    let mut planned: Vec<(&'static str, String, usize)> = Vec::new();
    let mut skipped = Vec::new();
    for sel in &opts.knobs {
        let knob = knobs::find(sel.knob)?;
        let values: Vec<String> = match &sel.values {
            Some(v) => v.clone(),
            None => knob.values.iter().map(|s| s.to_string()).collect(),
        };
        for value in values {
            let mut v = base;
            (knob.apply)(&mut v, &value)?;
            if v.accel.is_some() && animation.is_none() {
                let why = "the scene is not animated (give --animation NAME)";
                if sel.values.is_some() {
                    bail!("report: {} {value}: {why}", knob.name);
                }
                log::info!("report: {} {value} skipped: {why}", knob.name);
                skipped.push(format!("{} {value}: {why}", knob.name));
                continue;
            }
            let v = match concrete(v) {
                Ok(v) => v,
                Err(e) if knob.skip_unavailable && sel.values.is_none() => {
                    log::info!("report: {} {value} skipped: {e:#}", knob.name);
                    skipped.push(format!("{} {value}: {e:#}", knob.name));
                    continue;
                }
                Err(e) => return Err(e.context(format!("report: {} {value} cannot run", knob.name))),
            };
            let i = index_of(&mut variants, v, format!("{} {value}", knob.name));
            planned.push((knob.name, value, i));
        }
    }

    let aa_reference = if planned.iter().any(|(k, _, _)| *k == "aa") {
        let ss = opts.aa_reference;
        eprintln!("report: the aa knob's reference, the base settings {0}x{0} supersampled", ss.factor);
        let extent = ash::vk::Extent2D { width, height };
        let f = render_supersampled(ctx, &scene, &camera, extent, &base.settings, &ss)
            .context("report: the aa knob's supersampled reference")?;
        let ms = f.frame_ms();
        Some(AaReference { supersample: ss, ldr: LdrImage { width, height, rgb: f.rgb8().into_raw() }, ms })
    } else {
        None
    };

    let exposure = reference.settings.exposure;
    let mut renderers = Renderers(Vec::new());
    let mut truth = None;
    let result: Result<(Vec<Measured>, Vec<Row>, Option<attribution::Attribution>)> = (|| {
        if variants.iter().any(|(v, _)| v.budget_share.is_some()) {
            let renderer = renderers.get(ctx, &scene, width, height)?;
            let all = budget_cost_of_everything(ctx, renderer, &scene, &camera, &base.settings)?;
            eprintln!("report: the budget knob's shares are of {all:.0} (every visible object traced)");
            for (v, _) in &mut variants {
                if let Some(share) = v.budget_share {
                    v.settings.budget = Some(BudgetSettings {
                        fallback: Fallback::None,
                        ..BudgetSettings::paper(share * all)
                    });
                }
            }
        }
        let mut measured: Vec<Measured> = Vec::new();
        let started = std::time::Instant::now();
        let n = variants.len();
        let cache = opts.truth_cache.as_deref();
        for (i, (v, label)) in variants.iter().enumerate() {
            let e = measure::scaled_extent(width, height, v.scale);
            eprintln!(
                "report [{}/{n}] {label} ({}x{}, {:.0} s so far)",
                i + 1,
                e.width,
                e.height,
                started.elapsed().as_secs_f64()
            );
            let m = match (v.accel, animation) {
                _ if i == 0 && truth_mode => {
                    let renderer = renderers.get(ctx, &scene, e.width, e.height)?;
                    let samples = opts.reference.samples;
                    let (m, t) = truth::truth(ctx, renderer, &scene, &camera, v, samples, exposure, cache)?;
                    truth = Some(t);
                    Ok(m)
                }
                (Some(_), Some(animation)) => {
                    let playback = measure::Playback { animation, end: opts.job.time, fps: opts.job.fps };
                    let counts = (opts.warmup, opts.frames);
                    measure::measure_animated(ctx, &scene, playback, &camera, v, e, counts, opts.count_rays)
                }
                _ => {
                    let renderer = renderers.get(ctx, &scene, e.width, e.height)?;
                    let (w, f) = (opts.warmup, opts.frames);
                    measure::measure(ctx, renderer, &scene, &camera, v, w, f, opts.count_rays)
                }
            }
            .with_context(|| format!("report: measuring {label}"))?;
            eprintln!(
                "report [{}/{n}] {label}: {:.3} ms median, {:.3} ms p95 ({})",
                i + 1,
                m.timing.median,
                m.timing.p95,
                m.config
            );
            measured.push(m);
        }
        let mut rows = rows_against_reference(&planned, &measured, aa_reference.as_ref(), exposure)?;
        // The truth's own noise must stay under the errors it measures.
        while let Some(t) = truth.as_ref() {
            let smallest = rows
                .iter()
                .filter(|r| r.knob != "aa" && r.flip_mean > 0.0)
                .map(|r| r.flip_mean)
                .fold(1.0, f64::min);
            if t.noise() <= 0.5 * smallest || t.samples * 2 > opts.reference.max_samples {
                break;
            }
            eprintln!(
                "report: the reference's noise (ꟻLIP ~{:.5}) is over half the smallest error ({smallest:.5}): \
                 {} samples per pixel",
                t.noise(),
                t.samples * 2
            );
            let renderer = renderers.get(ctx, &scene, width, height)?;
            let (m, t) =
                truth::truth(ctx, renderer, &scene, &camera, &variants[0].0, t.samples * 2, exposure, cache)?;
            (measured[0], truth) = (m, Some(t));
            rows = rows_against_reference(&planned, &measured, aa_reference.as_ref(), exposure)?;
        }
        let attribution = match (&truth, opts.attribution_samples) {
            (Some(_), n) if n > 0 => {
                let renderer = renderers.get(ctx, &scene, width, height)?;
                // The base frame is measured already: its settings and image.
                let (settings, base) = (&measured[hybrid].variant.settings, &measured[hybrid].image);
                let truth = &measured[0].image;
                let a = attribution::run(ctx, renderer, &scene, &camera, settings, base, truth, exposure, n)
                    .context("report: the attribution of the default frame's error")?;
                Some(a)
            }
            _ => None,
        };
        Ok((measured, rows, attribution))
    })();
    renderers.destroy(ctx);
    let (measured, rows, attribution) = result?;
    let against_ref = |i: usize| metrics::compare_hdr(&measured[0].image, &measured[i].image, exposure);
    let check = metrics::compare_hdr(&measured[rt].image, &measured[hybrid].image, exposure)?;
    let e = &base.settings.effects;
    let convergence = match (convergence, &truth) {
        (Some(i), _) => {
            let conv = against_ref(i)?;
            let ef = &measured[i].variant.settings.effects;
            Distance {
                about: format!(
                    "the reference against max depth {}, min weight {}",
                    ef.max_depth,
                    plot::significant(ef.min_weight as f64, 3)
                ),
                flip_mean: conv.flip_mean,
                psnr: conv.psnr,
                ldr: conv.ldr,
            }
        }
        (None, Some(t)) => Distance {
            about: format!(
                "the first half of the reference's {} samples per pixel against the second (its own error is \
                 about half this)",
                t.samples
            ),
            flip_mean: t.halves_flip,
            psnr: t.halves_psnr,
            ldr: t.halves_ldr,
        },
        (None, None) => bail!("report: no convergence measure (internal)"),
    };
    Ok(Report {
        scene: opts.job.scene.clone(),
        device: ctx.caps.name.clone(),
        width,
        height,
        frames: opts.frames,
        warmup: opts.warmup,
        reference_exposure: exposure,
        reference_settings: opts.reference,
        self_check: Distance {
            about: format!(
                "hybrid against rt at the base settings (max depth {}, min weight {}, {})",
                e.max_depth, e.min_weight, measured[hybrid].config
            ),
            flip_mean: check.flip_mean,
            psnr: check.psnr,
            ldr: check.ldr,
        },
        convergence,
        truth,
        measured,
        base: hybrid,
        rows,
        skipped,
        aa_reference,
        attribution,
    })
}

/// Each planned knob value against the reference (`measured[0]`); the aa
/// rows against the supersampled base instead.
fn rows_against_reference(
    planned: &[(&'static str, String, usize)],
    measured: &[Measured],
    aa_reference: Option<&AaReference>,
    exposure: f32,
) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    for (knob, value, i) in planned.iter().cloned() {
        if let (true, Some(aa)) = (knob == "aa", aa_reference) {
            let m = &measured[i];
            let map = metrics::flip(&aa.ldr, &m.ldr).with_context(|| format!("comparing aa {value}"))?;
            let psnr = crate::image_diff::psnr_rgb8(&aa.ldr.rgb, &m.ldr.rgb, 3, None);
            // relMSE is a radiance measure; anti-aliasing changes no radiance.
            rows.push(Row { knob, value, measured: i, flip_mean: map.mean(), psnr, rel_mse: f64::NAN, map });
            continue;
        }
        let Errors { flip_mean, psnr, rel_mse, map, .. } =
            metrics::compare_hdr(&measured[0].image, &measured[i].image, exposure)
                .with_context(|| format!("comparing {knob} {value} with the reference"))?;
        rows.push(Row { knob, value, measured: i, flip_mean, psnr, rel_mse, map });
    }
    Ok(rows)
}

/// The `aa` knob's chart: its rows have their own reference.
pub const AA_PLOT: &str = "error_vs_time_aa.png";

/// Writes every output of `report` into `dir`; returns the files written.
pub fn write_all(report: &Report, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut files = Vec::new();
    let reference = dir.join("reference.png");
    let r = report.reference();
    let ldr = r.image.tone_mapped(report.reference_exposure);
    image::RgbImage::from_raw(ldr.width, ldr.height, ldr.rgb)
        .context("reference size")?
        .save(&reference)
        .with_context(|| format!("writing {}", reference.display()))?;
    files.push(reference);
    let mut maps = Vec::new();
    for row in report.worst_rows() {
        let name = write::error_map_name(row);
        let path = dir.join(&name);
        row.map.save_png(&path)?;
        maps.push((row.knob, row.value.clone(), name));
        files.push(path);
    }
    let plot = dir.join("error_vs_time.png");
    plot::error_vs_time(report, &plot, false)?;
    files.push(plot);
    if !plot::plotted_rows(report, true).is_empty() {
        let plot = dir.join(AA_PLOT);
        plot::error_vs_time(report, &plot, true)?;
        files.push(plot);
    }
    if let Some(a) = &report.attribution {
        let csv = dir.join("attribution.csv");
        std::fs::write(&csv, a.csv()).with_context(|| format!("writing {}", csv.display()))?;
        files.push(csv);
    }
    let csv = dir.join("report.csv");
    std::fs::write(&csv, write::csv(report)).with_context(|| format!("writing {}", csv.display()))?;
    files.push(csv);
    let md = dir.join("report.md");
    std::fs::write(&md, write::markdown(report, &maps))
        .with_context(|| format!("writing {}", md.display()))?;
    files.push(md);
    Ok(files)
}

/// `report`: runs it in its own context and writes `opts.out`.
pub fn report_command(gpu: &GpuOptions, opts: &ReportOptions) -> Result<()> {
    with_context(gpu, |ctx| {
        let report = run(ctx, opts)?;
        crate::app::check_validation(ctx)?;
        let files = write_all(&report, &opts.out)?;
        println!(
            "self-check, hybrid vs rt at equal settings: ꟻLIP {:.5}, PSNR {:.2} dB",
            report.self_check.flip_mean, report.self_check.psnr
        );
        for f in files {
            println!("wrote {}", f.display());
        }
        Ok(())
    })
}
