//! `report prt`: the ambient (SH irradiance and diffuse PRT) against a converged ray-traced reference
//! of the same view (`--reference-samples N --reference-bounces K`), all else equal, so ꟻLIP measures
//! the ambient's error only.
//!
//! Knobs (own table, like `knobs::KNOBS`): `bands`, `sh-samples` (N×N stratified MC or `exact`
//! quadrature), `transfer` (sh, prt-unshadowed, prt-shadowed, prt-interreflected-1/-2); their product
//! by default, one at a time with `--prt-sweep`. Per variant: precompute time (from a note beside the
//! cache file on a hit), SH projection time, GPU ms (frame, composite), ꟻLIP/PSNR. `prt_write`
//! writes tables, plots and pictures.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context as _, Result};

use super::knobs::{Knob, KnobSelection, Variant};
use super::measure::{self, Measured};
use super::metrics::{self, HdrImage};
use crate::app::{load_posed, with_context, GpuOptions, RenderJob};
use crate::gpu::env_sh::SH_BANDS;
use crate::gpu::shared::REFERENCE_SAMPLES_PER_FRAME;
use crate::prt::{default_cache_dir, CacheOutcome, PrtCache, PrtSettings};
use crate::render::{AmbientMode, EnvProjection, ReferenceSettings, RenderSettings, Renderer};
use crate::scene::sh::{project, Projection};
use crate::vk::Context;

/// The default reference when `--reference-samples` is not given: 1024
/// samples per pixel, paths of 3 rays (2 diffuse bounces beyond the
/// visibility ray, one more than the deepest PRT transfer here).
pub const DEFAULT_REFERENCE: ReferenceSettings = ReferenceSettings { samples: 1024, bounces: 3 };

/// The ambient's knobs, in report order.
pub const PRT_KNOBS: &[Knob] = &[
    Knob {
        name: "bands",
        about: "SH bands of the PRT transfer and the environment (bands² coefficients); the sh ambient \
                evaluates 3 bands only",
        values: &["1", "2", "3", "5", "7"],
        apply: |v, s| {
            let b: usize = s.parse().with_context(|| format!("bands '{s}': expected 1..=8"))?;
            crate::scene::sh::check_bands(b).with_context(|| format!("bands {b}"))?;
            v.settings.prt.bands = b;
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "sh-samples",
        about: "the environment's SH projection: N gives N×N stratified jittered Monte-Carlo samples, \
                exact the per-texel solid-angle quadrature",
        values: &["16", "64", "256", "exact"],
        apply: |v, s| {
            v.settings.prt.projection = parse_projection(s)?;
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "transfer",
        about: "sh (unshadowed SH irradiance, no PRT), prt-unshadowed, prt-shadowed, \
                prt-interreflected-K (K = 1..=16 bounces)",
        values: &["sh", "prt-unshadowed", "prt-shadowed", "prt-interreflected-1", "prt-interreflected-2"],
        apply: |v, s| {
            let (ambient, bounces) = parse_transfer(s)?;
            v.settings.ambient = ambient;
            v.settings.ambient_from_scene = false;
            if let Some(k) = bounces {
                v.settings.prt.bounces = k;
            }
            Ok(())
        },
        skip_unavailable: false,
    },
];

/// Most Monte-Carlo strata per side of the `sh-samples` knob.
const MAX_PROJECTION_N: u32 = 4096;

fn parse_projection(s: &str) -> Result<EnvProjection> {
    if s == "exact" {
        return Ok(EnvProjection::Exact);
    }
    match s.parse::<u32>() {
        Ok(n) if (1..=MAX_PROJECTION_N).contains(&n) => Ok(EnvProjection::MonteCarlo(n)),
        _ => bail!("sh-samples '{s}': expected exact or N in 1..={MAX_PROJECTION_N} (N×N samples)"),
    }
}

/// A transfer name: the ambient mode and, for interreflected, its bounces.
fn parse_transfer(s: &str) -> Result<(AmbientMode, Option<u32>)> {
    let expected = "expected traced, sh, prt-unshadowed, prt-shadowed or prt-interreflected-K (K = 1..=16)";
    Ok(match s {
        "traced" => (AmbientMode::Traced, None),
        "sh" => (AmbientMode::Sh, None),
        "prt-unshadowed" => (AmbientMode::PrtUnshadowed, None),
        "prt-shadowed" => (AmbientMode::PrtShadowed, None),
        _ => match s.strip_prefix("prt-interreflected-").map(str::parse::<u32>) {
            Some(Ok(k)) if (1..=crate::prt::MAX_BOUNCES).contains(&k) => {
                (AmbientMode::PrtInterreflected, Some(k))
            }
            _ => bail!("transfer '{s}': {expected}"),
        },
    })
}

pub fn find(name: &str) -> Result<&'static Knob> {
    PRT_KNOBS.iter().find(|k| k.name == name).with_context(|| {
        let names: Vec<_> = PRT_KNOBS.iter().map(|k| k.name).collect();
        format!("unknown knob '{name}' for report prt (knobs: {})", names.join(", "))
    })
}

/// `--knobs` under `--prt`: the same syntax as the main report's
/// (`bands=1:3,transfer`), over [`PRT_KNOBS`]; empty: every knob with
/// its full value list.
pub fn parse_selection(s: &str) -> Result<Vec<KnobSelection>> {
    super::knobs::parse_selection_in(s, PRT_KNOBS, find)
}

#[derive(Clone, Debug)]
pub struct PrtReportOptions {
    /// Scene, camera, size, environment and the base settings.
    pub job: RenderJob,
    pub frames: usize,
    pub warmup: usize,
    /// Knobs with their values; a knob left out stays at the base setting.
    pub knobs: Vec<KnobSelection>,
    /// One knob at a time around the base settings instead of the product.
    pub sweep: bool,
    pub reference: ReferenceSettings,
    pub out: PathBuf,
}

impl PrtReportOptions {
    pub fn new(job: RenderJob, out: impl Into<PathBuf>) -> Self {
        let knobs = parse_selection("").expect("every knob");
        let reference = job.settings.reference.unwrap_or(DEFAULT_REFERENCE);
        PrtReportOptions { job, frames: 10, warmup: 2, knobs, sweep: false, reference, out: out.into() }
    }
}

/// One knob setting of a variant, as given.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    pub transfer: String,
    pub bands: usize,
    pub sh_samples: String,
}

/// A precompute's cost: seconds, and whether this run computed it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Precompute {
    /// Seconds of the compute (from this run or the note beside the cache
    /// file); NaN when the cache had the transfer but no note.
    pub seconds: f64,
    /// False: loaded from the disk cache in this run.
    pub computed: bool,
}

pub struct PrtRow {
    pub setting: Setting,
    /// Index into `PrtReport::measured`.
    pub measured: usize,
    /// None for sh (no transfer).
    pub precompute: Option<Precompute>,
    /// The environment's projection at the row's bands and integrator, ms.
    pub projection_ms: f64,
    pub flip_mean: f64,
    pub psnr: f64,
    pub map: metrics::FlipMap,
}

pub struct PrtReport {
    pub scene: PathBuf,
    pub env: String,
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub warmup: usize,
    pub sweep: bool,
    pub prt_samples: u32,
    pub reference: ReferenceSettings,
    pub reference_seconds: f64,
    /// The reference at half its samples against the reference.
    pub convergence: (u32, f64, f64),
    pub exposure: f32,
    pub reference_image: HdrImage,
    pub environment: crate::scene::HdrImage,
    pub measured: Vec<Measured>,
    pub rows: Vec<PrtRow>,
    pub skipped: Vec<String>,
}

/// The variants to measure: the product of the selected values, or each
/// knob alone around the base.
/// The variants of a run with their settings, and the skipped ones (why).
type Plan = (Vec<(Variant, Setting)>, Vec<String>);

fn plan(opts: &PrtReportOptions, base: &Variant) -> Result<Plan> {
    let values = |name: &str| -> Vec<String> {
        match opts.knobs.iter().find(|k| k.knob == name) {
            Some(KnobSelection { values: Some(v), .. }) => v.clone(),
            Some(_) => {
                find(name).map(|k| k.values.iter().map(|s| s.to_string()).collect()).unwrap_or_default()
            }
            None => vec![],
        }
    };
    let base_setting = Setting {
        transfer: transfer_name(&base.settings),
        bands: base.settings.prt.bands,
        sh_samples: "exact".into(),
    };
    let mut combos: Vec<[Option<String>; 3]> = Vec::new();
    let names = ["transfer", "bands", "sh-samples"];
    if opts.sweep {
        for (k, name) in names.iter().enumerate() {
            for v in values(name) {
                let mut c: [Option<String>; 3] = Default::default();
                c[k] = Some(v);
                combos.push(c);
            }
        }
    } else {
        let or_base =
            |v: Vec<String>| if v.is_empty() { vec![None] } else { v.into_iter().map(Some).collect() };
        for t in or_base(values("transfer")) {
            for b in or_base(values("bands")) {
                for s in or_base(values("sh-samples")) {
                    combos.push([t.clone(), b.clone(), s.clone()]);
                }
            }
        }
    }
    let mut out: Vec<(Variant, Setting)> = Vec::new();
    let mut skipped = Vec::new();
    for c in combos {
        let mut v = *base;
        let mut s = base_setting.clone();
        for (k, value) in c.iter().enumerate() {
            if let Some(value) = value {
                (find(names[k])?.apply)(&mut v, value)?;
                match k {
                    0 => s.transfer = value.clone(),
                    1 => s.bands = v.settings.prt.bands,
                    _ => s.sh_samples = value.clone(),
                }
            }
        }
        if v.settings.ambient == AmbientMode::Sh && s.bands != SH_BANDS {
            let why = format!(
                "transfer sh, bands {}, sh-samples {}: the sh ambient evaluates {} bands only",
                s.bands, s.sh_samples, SH_BANDS
            );
            if !skipped.contains(&why) {
                skipped.push(why);
            }
            continue;
        }
        if !out.iter().any(|(x, _)| *x == v) {
            out.push((v, s));
        }
    }
    if out.is_empty() {
        bail!("report prt: no variant to run (every selected setting was skipped)");
    }
    Ok((out, skipped))
}

/// The transfer knob's name of the settings' ambient.
fn transfer_name(s: &RenderSettings) -> String {
    match s.ambient {
        AmbientMode::Traced => "traced".into(),
        AmbientMode::Sh => "sh".into(),
        AmbientMode::Constant => "constant".into(),
        AmbientMode::PrtUnshadowed => "prt-unshadowed".into(),
        AmbientMode::PrtShadowed => "prt-shadowed".into(),
        AmbientMode::PrtInterreflected => format!("prt-interreflected-{}", s.prt.bounces),
    }
}

/// The PRT settings a variant's frame precomputes (None: no transfer).
fn prt_settings(s: &RenderSettings) -> Option<PrtSettings> {
    s.ambient.prt_mode().map(|mode| PrtSettings {
        mode,
        bands: s.prt.bands,
        samples: s.prt.samples,
        bounces: s.prt.bounces,
    })
}

/// Gets `s`'s transfer into the disk cache, timing the compute; the
/// seconds go to a note beside the cache file so that a later run (another
/// environment map: the transfer does not depend on it) still reports them.
fn precompute(scene: &crate::scene::Scene, s: &PrtSettings) -> Result<Precompute> {
    let cache = PrtCache::new(default_cache_dir());
    let note = cache.path(crate::prt::cache_key(scene, s)).map(|p| p.with_extension("seconds"));
    let t = Instant::now();
    let (_, outcome) = cache.get(scene, s).with_context(|| format!("PRT precompute {s:?}"))?;
    let seconds = t.elapsed().as_secs_f64();
    match outcome {
        CacheOutcome::Computed => {
            if let Some(note) = &note {
                if let Err(e) = std::fs::write(note, format!("{seconds}\n")) {
                    log::warn!("report: cannot write {}: {e}", note.display());
                }
            }
            Ok(Precompute { seconds, computed: true })
        }
        CacheOutcome::Loaded => {
            let noted =
                note.and_then(|n| std::fs::read_to_string(n).ok()).and_then(|s| s.trim().parse().ok());
            Ok(Precompute { seconds: noted.unwrap_or(f64::NAN), computed: false })
        }
    }
}

/// Renders the reference from scratch: returns the image at half its
/// frames and at all of them, and the seconds it took.
fn render_reference(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &crate::scene::Scene,
    camera: &crate::scene::Camera,
    settings: &RenderSettings,
) -> Result<(HdrImage, HdrImage, f64)> {
    let r = settings.reference.context("a reference setting")?;
    renderer.reset_reference();
    let frames = r.frames();
    let half = (frames / 2).max(1);
    let start = Instant::now();
    let mut half_image = None;
    let mut out = None;
    for i in 1..=frames {
        let o = renderer.render(ctx, scene, camera, settings)?;
        if i == half {
            half_image = Some(HdrImage::from_rgba(o.width, o.height, &o.hdr).0);
        }
        if i % 16 == 0 {
            eprintln!("report prt: reference frame {i}/{frames}, {:.0} s", start.elapsed().as_secs_f64());
        }
        out = Some(o);
    }
    let out = out.context("no reference frame")?;
    let (full, non_finite) = HdrImage::from_rgba(out.width, out.height, &out.hdr);
    if non_finite > 0 {
        bail!("the reference has {non_finite} non-finite pixel(s)");
    }
    Ok((half_image.context("no half-way frame")?, full, start.elapsed().as_secs_f64()))
}

/// Runs the PRT report's renders and comparisons (writes nothing).
pub fn run(ctx: &Context, opts: &PrtReportOptions) -> Result<PrtReport> {
    if opts.frames < 5 {
        bail!("report: --frames {} is too few for a p95; use at least 5", opts.frames);
    }
    let (width, height) = (opts.job.width, opts.job.height);
    let extent = opts.job.extent()?;
    let (scene, _) = load_posed(&opts.job)?;
    let Some(map) = scene.environment.map.clone() else {
        bail!("report prt: {} has no environment map (give --env MAP.hdr)", opts.job.scene.display());
    };
    let env = scene.environment.map_path.as_ref().map_or("(scene)".into(), |p| p.display().to_string());
    let camera = opts.job.camera.resolve(&scene)?;
    let mut base_settings = RenderSettings { reference: None, ..opts.job.settings };
    base_settings.prt.projection = EnvProjection::Exact;
    let base = Variant::new(base_settings);
    let (variants, skipped) = plan(opts, &base)?;
    eprintln!("report prt: {} variants ({})", variants.len(), if opts.sweep { "sweeps" } else { "product" });

    // CPU side first: every distinct transfer and projection, timed.
    let mut precomputes: Vec<(PrtSettings, Precompute)> = Vec::new();
    let mut projections: Vec<((usize, EnvProjection), f64)> = Vec::new();
    for (v, _) in &variants {
        if let Some(s) = prt_settings(&v.settings) {
            if !precomputes.iter().any(|(x, _)| *x == s) {
                eprintln!("report prt: precompute {s:?}");
                precomputes.push((s, precompute(&scene, &s)?));
            }
        }
        let bands = if prt_settings(&v.settings).is_some() { v.settings.prt.bands } else { SH_BANDS };
        let key = (bands, v.settings.prt.projection);
        if !projections.iter().any(|(k, _)| *k == key) {
            let t = Instant::now();
            project(&map, &Projection { bands, ..Default::default() }, key.1.integrator())?;
            projections.push((key, t.elapsed().as_secs_f64() * 1e3));
        }
    }

    let reference_settings = RenderSettings {
        reference: Some(opts.reference),
        ambient: AmbientMode::Sh,
        ambient_from_scene: false,
        ..base.settings
    };
    let mut renderer = Renderer::new(ctx, &scene, extent)?;
    let result = (|| -> Result<(HdrImage, HdrImage, f64, Vec<Measured>)> {
        eprintln!(
            "report prt: the reference, {} samples per pixel, {} ray(s) per path",
            opts.reference.samples, opts.reference.bounces
        );
        let (half, reference, seconds) =
            render_reference(ctx, &mut renderer, &scene, &camera, &reference_settings)?;
        let mut measured = Vec::new();
        let started = Instant::now();
        for (i, (v, s)) in variants.iter().enumerate() {
            let m = measure::measure(ctx, &mut renderer, &scene, &camera, v, opts.warmup, opts.frames, false)
                .with_context(|| format!("report prt: measuring {s:?}"))?;
            eprintln!(
                "report prt [{}/{}] {} bands {} sh-samples {}: {:.3} ms median ({:.0} s so far)",
                i + 1,
                variants.len(),
                s.transfer,
                s.bands,
                s.sh_samples,
                m.timing.median,
                started.elapsed().as_secs_f64()
            );
            measured.push(m);
        }
        Ok((half, reference, seconds, measured))
    })();
    renderer.destroy(ctx);
    let (half, reference, reference_seconds, measured) = result?;

    let exposure = base.settings.exposure;
    let conv = metrics::compare_hdr(&reference, &half, exposure)?;
    let mut rows = Vec::new();
    for (i, (v, s)) in variants.into_iter().enumerate() {
        let e = metrics::compare_hdr(&reference, &measured[i].image, exposure)
            .with_context(|| format!("comparing {s:?} with the reference"))?;
        let p = prt_settings(&v.settings);
        let precompute = p.and_then(|p| precomputes.iter().find(|(x, _)| *x == p).map(|(_, c)| *c));
        let bands = if p.is_some() { v.settings.prt.bands } else { SH_BANDS };
        let key = (bands, v.settings.prt.projection);
        let projection_ms = projections.iter().find(|(k, _)| *k == key).map_or(f64::NAN, |(_, ms)| *ms);
        rows.push(PrtRow {
            setting: s,
            measured: i,
            precompute,
            projection_ms,
            flip_mean: e.flip_mean,
            psnr: e.psnr,
            map: e.map,
        });
    }
    Ok(PrtReport {
        scene: opts.job.scene.clone(),
        env,
        device: ctx.caps.name.clone(),
        width,
        height,
        frames: opts.frames,
        warmup: opts.warmup,
        sweep: opts.sweep,
        prt_samples: base.settings.prt.samples,
        reference: opts.reference,
        reference_seconds,
        convergence: (
            (opts.reference.frames() / 2).max(1) * REFERENCE_SAMPLES_PER_FRAME,
            conv.flip_mean,
            conv.psnr,
        ),
        exposure,
        reference_image: reference,
        environment: map,
        measured,
        rows,
        skipped,
    })
}

/// `report prt`: runs it in its own context and writes `opts.out`.
pub fn command(gpu: &GpuOptions, opts: &PrtReportOptions) -> Result<()> {
    with_context(gpu, |ctx| {
        let report = run(ctx, opts)?;
        crate::app::check_validation(ctx)?;
        for f in super::prt_write::write_all(&report, &opts.out)? {
            println!("wrote {}", f.display());
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn applied(knob: &str, value: &str) -> Result<RenderSettings> {
        let mut v = Variant::new(RenderSettings::default());
        (find(knob)?.apply)(&mut v, value)?;
        Ok(v.settings)
    }

    #[test]
    fn knobs_apply_and_reject_bad_values() {
        for k in PRT_KNOBS {
            for v in k.values {
                applied(k.name, v).unwrap_or_else(|e| panic!("{} {v}: {e}", k.name));
            }
        }
        assert_eq!(applied("bands", "7").unwrap().prt.bands, 7);
        assert_eq!(applied("sh-samples", "64").unwrap().prt.projection, EnvProjection::MonteCarlo(64));
        assert_eq!(applied("sh-samples", "exact").unwrap().prt.projection, EnvProjection::Exact);
        let s = applied("transfer", "prt-interreflected-2").unwrap();
        assert_eq!(
            (s.ambient, s.prt.bounces, s.ambient_from_scene),
            (AmbientMode::PrtInterreflected, 2, false)
        );
        assert_eq!(applied("transfer", "prt-shadowed").unwrap().ambient, AmbientMode::PrtShadowed);
        for (k, bad, says) in [
            ("bands", "9", "bands 9"),
            ("bands", "x", "bands 'x'"),
            ("sh-samples", "0", "sh-samples '0'"),
            ("sh-samples", "exactly", "expected exact or N"),
            ("transfer", "prt-interreflected-0", "transfer 'prt-interreflected-0'"),
            ("transfer", "shadowed", "expected traced, sh, prt-unshadowed"),
        ] {
            let e = format!("{:#}", applied(k, bad).unwrap_err());
            assert!(e.contains(says), "{k} {bad}: {e}");
        }
        assert!(parse_selection("bands=1:3,transfer").is_ok());
        assert!(format!("{:#}", parse_selection("max-depth").unwrap_err())
            .contains("bands, sh-samples, transfer"));
        assert!(parse_selection("bands=3:99").is_err());
        assert!(parse_selection("bands,bands").is_err());
    }

    #[test]
    fn plan_is_the_product_or_the_sweeps() {
        let job = RenderJob::new("s.toml", 16, 9);
        let sel = |s: &str| parse_selection(s).unwrap();
        let mut opts = PrtReportOptions::new(job, "out");
        let base = Variant::new(RenderSettings { ambient: AmbientMode::PrtShadowed, ..Default::default() });
        // 5 bands x 4 projections x 4 PRT transfers + sh at 3 bands x 4.
        let (v, skipped) = plan(&opts, &base).unwrap();
        assert_eq!(v.len(), 5 * 4 * 4 + 4);
        assert_eq!(skipped.len(), 4 * 4);
        opts.knobs = sel("bands=1:3,transfer=prt-unshadowed:prt-shadowed");
        let (v, _) = plan(&opts, &base).unwrap();
        let got: Vec<_> = v.iter().map(|(_, s)| (s.transfer.as_str(), s.bands)).collect();
        assert_eq!(
            got,
            [("prt-unshadowed", 1), ("prt-unshadowed", 3), ("prt-shadowed", 1), ("prt-shadowed", 3)]
        );
        opts.sweep = true;
        // The base (prt-shadowed, 3 bands) once.
        let (v, _) = plan(&opts, &base).unwrap();
        assert_eq!(v.len(), 3);
        opts.knobs = sel("transfer=sh,bands=5");
        opts.sweep = false;
        assert!(plan(&opts, &base).unwrap_err().to_string().contains("no variant"));
    }
}
