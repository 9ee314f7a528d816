//! `report stability`: the scene's stiff and extreme variants (far from
//! the origin, tiny and huge, grazing and facing mirrors, IOR near 1, total
//! internal reflection, a 1e5 environment texel, emission past half-float,
//! tiny and zero-area triangles, a wall at the camera) rendered on every
//! available backend, each compared with its canonical case and checked
//! against thresholds stated in `report.md`. `cases` builds the variants,
//! `write` the tables. See README "Report".

pub mod cases;
pub mod write;

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};

use super::knobs::Variant;
use super::measure::{self, Measured};
use super::metrics::{self, HdrImage};
use crate::app::{load_posed, resolve_shading, with_context, GpuOptions, RenderJob};
use crate::render::shading::{Backend, Mode};
use crate::render::{RenderSettings, Renderer};
use crate::vk::Context;
use cases::{Against, Case, Check};

#[derive(Clone, Debug)]
pub struct StabilityOptions {
    /// Scene, camera, size and base settings (their backend is ignored:
    /// every available one runs).
    pub job: RenderJob,
    /// Timed frames per case and backend (>= 3), after `warmup`.
    pub frames: usize,
    pub warmup: usize,
    /// Case names (empty: every case); canonicals are added.
    pub cases: Vec<String>,
    pub out: PathBuf,
}

impl StabilityOptions {
    pub fn new(job: RenderJob, out: impl Into<PathBuf>) -> StabilityOptions {
        StabilityOptions { job, frames: 5, warmup: 1, cases: Vec::new(), out: out.into() }
    }
}

/// One case on one backend.
pub struct Row {
    pub case: &'static str,
    pub backend: String,
    /// What the image was compared with ("origin", "rt mode", ...).
    pub against: String,
    pub finite_pct: f64,
    pub black_pct: f64,
    pub white_pct: f64,
    pub flip_mean: f64,
    pub psnr: f64,
    pub max_ldr_diff: u8,
    /// Share (percent) of pixels with an 8-bit channel off by more than
    /// [`write::MARGINAL_DIFF`].
    pub pct_far_off: f64,
    pub ms_median: f64,
    pub non_finite: usize,
    /// The checks that failed, in words; empty = pass.
    pub failed: Vec<String>,
    /// Set when the case could not be rendered or compared.
    pub error: Option<String>,
}

impl Row {
    pub fn pass(&self) -> bool {
        self.failed.is_empty() && self.error.is_none()
    }
}

/// What `report stability` measured.
pub struct Stability {
    pub scene: PathBuf,
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub warmup: usize,
    pub exposure: f32,
    /// Whether the scene has textures (what explains some differences).
    pub textured: bool,
    /// (name, about, against, checks) of every case, in report order.
    pub cases: Vec<(&'static str, String, Against, Vec<Check>)>,
    pub rows: Vec<Row>,
    /// Backends not run, with why.
    pub skipped: Vec<String>,
    /// Each case's tone-mapped image per backend (for the files).
    pub images: Vec<(String, metrics::LdrImage)>,
}

/// A case rendered on one backend: the hybrid frame and, when compared
/// with pure RT, the rt frame.
struct Rendered {
    case: usize,
    backend: String,
    hybrid: Result<Measured>,
    rt: Option<Result<Measured>>,
}

/// Share (percent) of pixels whose 8-bit channels all equal `v`.
fn share_all(img: &metrics::LdrImage, v: u8) -> f64 {
    let n = img.rgb.chunks_exact(3).filter(|p| p.iter().all(|&c| c == v)).count();
    100.0 * n as f64 / (img.rgb.len() / 3).max(1) as f64
}

/// The backends the device can run for `scene`, and notes for the others.
fn backends(
    ctx: &Context,
    scene: &crate::scene::Scene,
    base: &RenderSettings,
) -> (Vec<Backend>, Vec<String>) {
    let (mut ok, mut skipped) = (Vec::new(), Vec::new());
    for b in [Backend::Query, Backend::Pipeline, Backend::Compute] {
        match resolve_shading(ctx, scene, &RenderSettings { backend: b, ..*base }) {
            Ok(_) => ok.push(b),
            Err(e) => {
                log::info!("stability: backend {b:?} skipped: {e:#}");
                skipped.push(format!("{}: {e:#}", format!("{b:?}").to_lowercase()));
            }
        }
    }
    (ok, skipped)
}

/// Renders every case on every available backend and compares them (writes
/// only the case files: OBJ meshes and .hdr maps in `opts.out/cases/`).
pub fn run(ctx: &Context, opts: &StabilityOptions) -> Result<Stability> {
    if opts.frames < 3 {
        bail!("report stability: --frames {} is too few for a median; use at least 3", opts.frames);
    }
    let extent = opts.job.extent()?;
    let (scene, _) = load_posed(&opts.job)?;
    let camera = opts.job.camera.resolve(&scene)?;
    let case_dir = opts.out.join("cases");
    std::fs::create_dir_all(&case_dir).with_context(|| format!("creating {}", case_dir.display()))?;
    let cases = cases::build(&scene, &camera, &opts.cases, &case_dir)?;
    let base = RenderSettings { mode: Mode::Hybrid, ..opts.job.settings };
    let (available, skipped) = backends(ctx, &scene, &base);
    if available.is_empty() {
        bail!("report stability: no ray backend can run on {}: {}", ctx.caps.name, skipped.join("; "));
    }

    let n = cases.len();
    let started = std::time::Instant::now();
    let mut rendered: Vec<Rendered> = Vec::new();
    for (i, case) in cases.iter().enumerate() {
        eprintln!(
            "stability [{}/{n}] {}: {} ({:.0} s so far)",
            i + 1,
            case.name,
            case.about,
            started.elapsed().as_secs_f64()
        );
        let mut renderer = match Renderer::new(ctx, &case.scene, extent) {
            Ok(r) => r,
            Err(e) => {
                let msg = format!("{e:#}");
                log::warn!("stability: {}: {msg}", case.name);
                for b in &available {
                    let backend = format!("{b:?}").to_lowercase();
                    let err = || Err(anyhow::anyhow!("creating the renderer: {msg}"));
                    rendered.push(Rendered { case: i, backend, hybrid: err(), rt: None });
                }
                continue;
            }
        };
        for &b in &available {
            let mut settings = RenderSettings { backend: b, ..base };
            if let Some((depth, weight)) = case.depth {
                (settings.effects.max_depth, settings.effects.min_weight) = (depth, weight);
            }
            let backend = format!("{b:?}").to_lowercase();
            let variant = Variant::new(settings);
            let hybrid = measure::measure(
                ctx,
                &mut renderer,
                &case.scene,
                &case.camera,
                &variant,
                opts.warmup,
                opts.frames,
                false,
            )
            .with_context(|| format!("{} on {backend}", case.name));
            let rt = (case.against == Against::Rt).then(|| {
                let v = Variant::new(RenderSettings { mode: Mode::Rt, ..settings });
                measure::measure(ctx, &mut renderer, &case.scene, &case.camera, &v, 0, 1, false)
                    .with_context(|| format!("{} in rt mode on {backend}", case.name))
            });
            match &hybrid {
                Ok(m) => eprintln!(
                    "stability [{}/{n}] {} on {backend}: {:.3} ms median, {} non-finite pixel(s)",
                    i + 1,
                    case.name,
                    m.timing.median,
                    m.non_finite
                ),
                Err(e) => eprintln!("stability [{}/{n}] {} on {backend}: failed: {e:#}", i + 1, case.name),
            }
            rendered.push(Rendered { case: i, backend, hybrid, rt });
        }
        renderer.destroy(ctx);
    }
    let exposure = base.exposure;
    let mut rows = Vec::new();
    let mut images = Vec::new();
    for r in &rendered {
        let case = &cases[r.case];
        let row = compare(case, r, &cases, &rendered, exposure);
        if let Ok(m) = &r.hybrid {
            images.push((format!("{}_{}", case.name, r.backend), m.image.tone_mapped(exposure)));
        }
        rows.push(row);
    }
    Ok(Stability {
        scene: opts.job.scene.clone(),
        device: ctx.caps.name.clone(),
        width: extent.width,
        height: extent.height,
        frames: opts.frames,
        warmup: opts.warmup,
        exposure,
        textured: !scene.textures.is_empty(),
        cases: cases.iter().map(|c| (c.name, c.about.clone(), c.against.clone(), c.checks.clone())).collect(),
        rows,
        skipped,
        images,
    })
}

/// The row of one rendered case: its shares, its error against what it is
/// compared with, and the checks.
fn compare(case: &Case, r: &Rendered, cases: &[Case], all: &[Rendered], exposure: f32) -> Row {
    let mut row = Row {
        case: case.name,
        backend: r.backend.clone(),
        against: match &case.against {
            Against::Case(c) => c.to_string(),
            Against::Rt => "rt mode".into(),
        },
        finite_pct: f64::NAN,
        black_pct: f64::NAN,
        white_pct: f64::NAN,
        flip_mean: f64::NAN,
        psnr: f64::NAN,
        max_ldr_diff: 0,
        pct_far_off: f64::NAN,
        ms_median: f64::NAN,
        non_finite: 0,
        failed: Vec::new(),
        error: None,
    };
    let m = match &r.hybrid {
        Ok(m) => m,
        Err(e) => {
            row.error = Some(format!("{e:#}"));
            return row;
        }
    };
    let pixels = (m.width as usize * m.height as usize).max(1);
    row.non_finite = m.non_finite;
    row.finite_pct = 100.0 * (pixels - m.non_finite) as f64 / pixels as f64;
    row.ms_median = m.timing.median;
    let ldr = m.image.tone_mapped(exposure);
    (row.black_pct, row.white_pct) = (share_all(&ldr, 0), share_all(&ldr, 255));
    // The frame of case `name` on this backend.
    let hybrid_of = |name: &str| -> Result<&Measured> {
        let i = cases.iter().position(|c| c.name == name).with_context(|| format!("no case {name}"))?;
        let other = all.iter().find(|o| o.case == i && o.backend == r.backend).context("not rendered")?;
        other.hybrid.as_ref().map_err(|e| anyhow::anyhow!("{name} failed: {e:#}"))
    };
    let reference: Result<&HdrImage> = match &case.against {
        Against::Case(c) => hybrid_of(c).map(|m| &m.image),
        Against::Rt => match &r.rt {
            Some(Ok(rt)) => Ok(&rt.image),
            Some(Err(e)) => Err(anyhow::anyhow!("{e:#}")),
            None => Err(anyhow::anyhow!("rt mode not rendered")),
        },
    };
    let errors = reference.and_then(|reference| {
        let e = metrics::compare_hdr(reference, &m.image, exposure)?;
        let (a, b) = (reference.tone_mapped(exposure), m.image.tone_mapped(exposure));
        let (_, far) = crate::image_diff::diff_stats(&a.rgb, &b.rgb, 3, write::MARGINAL_DIFF);
        Ok((e, far))
    });
    match errors {
        Ok((e, far)) => {
            (row.flip_mean, row.psnr, row.max_ldr_diff) = (e.flip_mean, e.psnr, e.ldr.max);
            row.pct_far_off = 100.0 * far;
        }
        Err(e) => {
            row.error = Some(format!("comparing with {}: {e:#}", row.against));
            return row;
        }
    }
    if m.non_finite > 0 {
        row.failed.push(format!("{} non-finite pixel(s)", m.non_finite));
    }
    for check in &case.checks {
        let ok = match check {
            Check::PsnrAtLeast(db) => row.psnr >= *db,
            Check::MaxLdrDiff(d) => row.max_ldr_diff <= *d,
            Check::BlackNotAbove(c, margin) | Check::WhiteNotAbove(c, margin) => {
                let black = matches!(check, Check::BlackNotAbove(..));
                match hybrid_of(c) {
                    Ok(o) => {
                        let other = share_all(&o.image.tone_mapped(exposure), if black { 0 } else { 255 });
                        let own = if black { row.black_pct } else { row.white_pct };
                        own <= other + margin
                    }
                    Err(_) => false,
                }
            }
        };
        if !ok {
            let got = match check {
                Check::PsnrAtLeast(_) => format!("{:.2} dB", row.psnr),
                Check::MaxLdrDiff(_) => format!("{}", row.max_ldr_diff),
                Check::BlackNotAbove(..) => format!("{:.2} %", row.black_pct),
                Check::WhiteNotAbove(..) => format!("{:.2} %", row.white_pct),
            };
            row.failed.push(format!("{} (got {got})", check.describe()));
        }
    }
    row
}

/// `report stability`: runs it in its own context and writes `opts.out`.
pub fn stability_command(gpu: &GpuOptions, opts: &StabilityOptions) -> Result<()> {
    with_context(gpu, |ctx| {
        let report = run(ctx, opts)?;
        crate::app::check_validation(ctx)?;
        let files = write::write_all(&report, &opts.out)?;
        let failed = report.rows.iter().filter(|r| !r.pass()).count();
        println!("stability: {} of {} case/backend rows pass", report.rows.len() - failed, report.rows.len());
        for f in files {
            println!("wrote {}", f.display());
        }
        Ok(())
    })
}
