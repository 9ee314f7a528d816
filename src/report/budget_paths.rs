//! `report budget-paths`: the budget's image error against run time along the scene's camera path.
//! Per mode (paper; effects; effects with raster fallback) and share of the full cost, one renderer
//! (so selection, stickiness and cost model carry across frames, as in the viewer) renders `warmup`
//! frames, then `frames` path points, each compared with the full-effects frame there. Per run: frame
//! ms (median, p95), ray-stage ms, `heuristic` ms and share, mean ꟻLIP and PSNR. Shares are in the
//! mode's unit: effects mode of the full-effects median ray-stage ms, paper mode of the cost units of
//! every visible object at the path's start. Raster-only and full effects are the curve's ends.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};

use super::measure::median_p95;
use super::metrics::{flip, psnr_hdr, HdrImage, LdrImage};
use crate::app::{load_posed, with_context, GpuOptions, RenderJob};
use crate::render::budget::{BudgetMode, BudgetSettings, Fallback};
use crate::render::shading::Effects;
use crate::render::{FrameOutput, RenderSettings, Renderer};
use crate::scene::{camera, Camera, Scene};
use crate::vk::Context;

pub struct BudgetPathOptions {
    pub job: RenderJob,
    pub out: PathBuf,
    /// Points measured along the camera path.
    pub frames: usize,
    /// Frames at the path's start before measuring (calibration, selection).
    pub warmup: usize,
    /// Budgets as shares of the cost of tracing everything.
    pub shares: Vec<f64>,
}

/// The budget modes compared: the paper (whole objects, no fallback),
/// effects mode without and with the raster fallback.
pub struct ModeRun {
    pub label: &'static str,
    pub mode: BudgetMode,
    pub fallback: Fallback,
}

pub const MODES: [ModeRun; 3] = [
    ModeRun { label: "paper", mode: BudgetMode::Paper, fallback: Fallback::None },
    ModeRun { label: "effects", mode: BudgetMode::Effects, fallback: Fallback::None },
    ModeRun { label: "effects+fallback", mode: BudgetMode::Effects, fallback: Fallback::Raster },
];

/// One run along the path.
#[derive(Clone, Debug)]
pub struct PathRun {
    /// "paper", "effects", or the ends: "raster only", "full effects".
    pub label: String,
    pub share: Option<f64>,
    pub budget: Option<f64>,
    pub frame_ms: (f64, f64),
    pub ray_ms: f64,
    pub heuristic_ms: f64,
    /// Median over frames of heuristic ms / frame ms.
    pub heuristic_share: f64,
    pub flip_mean: f64,
    pub psnr: f64,
    /// Effects mode: frames whose ray stages took T within +-10%.
    pub within_10pct: Option<usize>,
}

struct Frame {
    ldr: LdrImage,
    hdr: HdrImage,
    ms: f64,
    ray_ms: f64,
    heuristic_ms: f64,
}

fn frame_of(out: &FrameOutput) -> Frame {
    Frame {
        ldr: LdrImage { width: out.width, height: out.height, rgb: out.rgb8().into_raw() },
        hdr: HdrImage::from_rgba(out.width, out.height, &out.hdr).0,
        ms: out.frame_ms(),
        ray_ms: out.budgeted_ms(),
        heuristic_ms: out.pass_ms("heuristic"),
    }
}

/// The path's cameras: `frames` points from its start to its end (the
/// scene camera when the scene has no path).
fn cameras(scene: &Scene, base: &Camera, frames: usize) -> Vec<Camera> {
    (0..frames)
        .map(|i| {
            let t = if frames > 1 { i as f32 / (frames - 1) as f32 } else { 0.0 };
            camera::on_path(&scene.camera_path, t, base)
        })
        .collect()
}

/// Renders `warmup` frames at the first camera, then one per camera.
fn run_path(
    ctx: &Context,
    scene: &Scene,
    cams: &[Camera],
    extent: ash::vk::Extent2D,
    settings: &RenderSettings,
    warmup: usize,
) -> Result<(Vec<Frame>, Renderer)> {
    let mut frames = Vec::new();
    let r = crate::vk::built(ctx, Renderer::new(ctx, scene, extent)?, |r| {
        for _ in 0..warmup {
            r.render(ctx, scene, &cams[0], settings)?;
        }
        for c in cams {
            frames.push(frame_of(&r.render(ctx, scene, c, settings)?));
        }
        Ok(())
    })?;
    Ok((frames, r))
}

fn summarize(
    label: &str,
    share: Option<f64>,
    budget: Option<&BudgetSettings>,
    frames: &[Frame],
    reference: &[Frame],
) -> Result<PathRun> {
    let ms: Vec<f64> = frames.iter().map(|f| f.ms).collect();
    let med = |v: Vec<f64>| median_p95(&v).0;
    let mut flips = Vec::new();
    let mut psnrs = Vec::new();
    for (f, r) in frames.iter().zip(reference) {
        flips.push(flip(&r.ldr, &f.ldr)?.mean());
        psnrs.push(psnr_hdr(&r.hdr, &f.hdr));
    }
    // Identical frames have an infinite PSNR: the mean over finite ones,
    // infinite only when every frame is identical.
    let finite: Vec<f64> = psnrs.iter().copied().filter(|p| p.is_finite()).collect();
    let psnr =
        if finite.is_empty() { f64::INFINITY } else { finite.iter().sum::<f64>() / finite.len() as f64 };
    let within_10pct = budget
        .filter(|b| b.mode == BudgetMode::Effects && b.budget.is_finite())
        .map(|b| frames.iter().filter(|f| (f.ray_ms / b.budget - 1.0).abs() <= 0.1).count());
    Ok(PathRun {
        label: label.to_string(),
        share,
        budget: budget.map(|b| b.budget),
        frame_ms: median_p95(&ms),
        ray_ms: med(frames.iter().map(|f| f.ray_ms).collect()),
        heuristic_ms: med(frames.iter().map(|f| f.heuristic_ms).collect()),
        heuristic_share: med(frames.iter().map(|f| f.heuristic_ms / f.ms.max(1e-9)).collect()),
        flip_mean: flips.iter().sum::<f64>() / flips.len().max(1) as f64,
        psnr,
        within_10pct,
    })
}

/// Runs every mode and share along the path (writes nothing).
pub fn run(ctx: &Context, opts: &BudgetPathOptions) -> Result<Vec<PathRun>> {
    if opts.frames < 2 {
        bail!("report budget-paths: --frames {} is too few for a path; use at least 2", opts.frames);
    }
    let extent = opts.job.extent()?;
    let (scene, _) = load_posed(&opts.job)?;
    let base_camera = opts.job.camera.resolve(&scene)?;
    if scene.camera_path.is_empty() {
        log::warn!("{}: no camera path; every frame is the scene camera's view", opts.job.scene.display());
    }
    let cams = cameras(&scene, &base_camera, opts.frames);
    let full = RenderSettings { budget: None, ..opts.job.settings };
    eprintln!("report budget-paths: full effects along the path ({} frames)", opts.frames);
    let (reference, mut r) = run_path(ctx, &scene, &cams, extent, &full, opts.warmup)?;
    // Paper mode's unit: its cost of everything visible at the path's start.
    let paper_all = (|| {
        let s = RenderSettings { budget: Some(BudgetSettings::paper(f64::INFINITY)), ..full };
        r.render(ctx, &scene, &cams[0], &s)?;
        r.budget_report().map(|b| b.selection.spent).context("no budget report: nothing is traced?")
    })();
    r.destroy(ctx);
    let paper_all = paper_all?;
    let ray_all = median_p95(&reference.iter().map(|f| f.ray_ms).collect::<Vec<_>>()).0;
    let mut runs = vec![summarize("full effects", None, None, &reference, &reference)?];
    let none = Effects { shadows: false, reflections: false, refractions: false, ..full.effects };
    eprintln!("report budget-paths: raster only");
    let (raster, mut r) =
        run_path(ctx, &scene, &cams, extent, &RenderSettings { effects: none, ..full }, opts.warmup)?;
    r.destroy(ctx);
    runs.push(summarize("raster only", None, None, &raster, &reference)?);
    let total = MODES.len() * opts.shares.len();
    for (m, mode) in MODES.iter().enumerate() {
        for (k, &share) in opts.shares.iter().enumerate() {
            let all = if mode.mode == BudgetMode::Paper { paper_all } else { ray_all };
            let b = BudgetSettings {
                mode: mode.mode,
                budget: share * all,
                stickiness: 0.0,
                fallback: mode.fallback,
            };
            eprintln!(
                "report budget-paths [{}/{total}]: {} mode, share {share} (T = {:.3})",
                m * opts.shares.len() + k + 1,
                mode.label,
                b.budget
            );
            let settings = RenderSettings { budget: Some(b), ..full };
            let (frames, mut r) = run_path(ctx, &scene, &cams, extent, &settings, opts.warmup)?;
            r.destroy(ctx);
            runs.push(summarize(mode.label, Some(share), Some(&b), &frames, &reference)?);
        }
    }
    Ok(runs)
}

/// The table (markdown).
pub fn table(opts: &BudgetPathOptions, device: &str, runs: &[PathRun]) -> String {
    let mut s = format!(
        "# Ray-tracing budget along the camera path: {}\n\n{}x{}, {} frames along the path after {} at its \
         start, device {device}, backend {:?}. Error: against the full-effects frame of the same point. \
         Shares: of the cost of tracing everything in the mode's unit (effects: the full-effects frames' \
         median ray-stage ms; paper: its cost units at the path's start).\n\n",
        opts.job.scene.display(),
        opts.job.width,
        opts.job.height,
        opts.frames,
        opts.warmup,
        opts.job.settings.backend
    );
    s.push_str(
        "| mode | share | T | frame ms median | p95 | ray stages ms | heuristic ms | heuristic share | ꟻLIP mean | PSNR dB | ray stages within ±10% of T |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let opt = |v: Option<f64>, p: usize| v.map_or("–".to_string(), |v| format!("{v:.p$}"));
    for r in runs {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.3} | {:.2}% | {:.4} | {:.1} | {} |",
            r.label,
            opt(r.share, 2),
            opt(r.budget, 2),
            r.frame_ms.0,
            r.frame_ms.1,
            r.ray_ms,
            r.heuristic_ms,
            r.heuristic_share * 100.0,
            r.flip_mean,
            r.psnr,
            r.within_10pct.map_or("–".to_string(), |n| format!("{n} of {}", opts.frames))
        );
    }
    s
}

/// The runs as CSV.
pub fn csv(runs: &[PathRun]) -> String {
    let mut s = String::from(
        "mode,share,budget,frame_ms_median,frame_ms_p95,ray_ms_median,heuristic_ms_median,heuristic_share,flip_mean,psnr_db,within_10pct\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
    for r in runs {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{}",
            r.label,
            opt(r.share),
            opt(r.budget),
            r.frame_ms.0,
            r.frame_ms.1,
            r.ray_ms,
            r.heuristic_ms,
            r.heuristic_share,
            r.flip_mean,
            r.psnr,
            r.within_10pct.map_or(String::new(), |n| n.to_string())
        );
    }
    s
}

/// `report budget-paths`: runs, then writes budget_paths.{md,csv,png}.
pub fn command(gpu: &GpuOptions, opts: &BudgetPathOptions) -> Result<()> {
    with_context(gpu, |ctx| {
        let runs = run(ctx, opts)?;
        std::fs::create_dir_all(&opts.out).with_context(|| format!("creating {}", opts.out.display()))?;
        let md = table(opts, &ctx.caps.name, &runs);
        let write = |name: &str, text: &str| {
            let p = opts.out.join(name);
            std::fs::write(&p, text).with_context(|| format!("writing {}", p.display()))?;
            println!("wrote {}", p.display());
            Ok::<_, anyhow::Error>(())
        };
        write("budget_paths.md", &md)?;
        write("budget_paths.csv", &csv(&runs))?;
        let series: Vec<super::plot::Series> = std::iter::once("raster only")
            .chain(MODES.iter().map(|m| m.label))
            .chain(std::iter::once("full effects"))
            .map(|label| super::plot::Series {
                label: label.to_string(),
                points: runs
                    .iter()
                    .filter(|r| r.label == label)
                    .map(|r| (r.frame_ms.0, r.flip_mean, r.share.map_or(String::new(), |s| format!("{s}"))))
                    .collect(),
            })
            .collect();
        let png = opts.out.join("budget_paths.png");
        let title = format!(
            "Budget along the path: {} ({}x{}, {})",
            opts.job.scene.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
            opts.job.width,
            opts.job.height,
            ctx.caps.name
        );
        super::plot::curves(
            &png,
            &title,
            "median GPU frame time (ms)",
            "FLIP mean against full effects",
            &series,
        )?;
        println!("wrote {}", png.display());
        print!("{md}");
        crate::app::check_validation(ctx)
    })
}
