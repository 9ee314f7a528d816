//! What `report prt` writes: `prt.md`, `prt.csv`, two plots (ꟻLIP
//! against the GPU frame time and against the precompute time) and the
//! pictures: the environment, its SH radiance reconstruction at 3 and 7
//! bands and the 3-band irradiance (equirect, 256x128, one exposure), the
//! reference, and each transfer at 3 bands / exact projection with its
//! ꟻLIP map.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use glam::DVec3;

use super::metrics::{HdrImage, LdrImage};
use super::plot::{self, significant, Series};
use super::prt::{PrtReport, PrtRow};
use crate::scene::sh::{project_quadrature, texel_dir, Projection};

/// The equirect pictures' size.
const PANO: (u32, u32) = (256, 128);

fn save(ldr: &LdrImage, path: &Path) -> Result<()> {
    image::RgbImage::from_raw(ldr.width, ldr.height, ldr.rgb.clone())
        .context("image size")?
        .save(path)
        .with_context(|| format!("writing {}", path.display()))
}

/// `map` box-filtered down to `PANO` (a sun texel is averaged, not lost).
fn downsampled(map: &crate::scene::HdrImage) -> HdrImage {
    let (w, h) = PANO;
    let mut rgb = vec![0f32; (w * h * 3) as usize];
    for y in 0..h {
        for x in 0..w {
            let (x0, x1) = (x * map.width / w, ((x + 1) * map.width / w).max(x * map.width / w + 1));
            let (y0, y1) = (y * map.height / h, ((y + 1) * map.height / h).max(y * map.height / h + 1));
            let mut sum = [0f64; 3];
            for sy in y0..y1.min(map.height) {
                for sx in x0..x1.min(map.width) {
                    let i = ((sy * map.width + sx) * 3) as usize;
                    for (s, v) in sum.iter_mut().zip(&map.rgb[i..i + 3]) {
                        *s += *v as f64;
                    }
                }
            }
            let n = ((y1.min(map.height) - y0) * (x1.min(map.width) - x0)).max(1) as f64;
            let o = ((y * w + x) * 3) as usize;
            for (d, s) in rgb[o..o + 3].iter_mut().zip(sum) {
                *d = (s / n) as f32;
            }
        }
    }
    HdrImage { width: w, height: h, rgb }
}

/// An exposure that puts the map's log-average luminance at 0.18.
fn auto_exposure(img: &HdrImage) -> f32 {
    let n = (img.rgb.len() / 3).max(1) as f64;
    let log_sum: f64 = img
        .rgb
        .chunks_exact(3)
        .map(|p| (1e-4 + 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64).ln())
        .sum();
    (0.18 / (log_sum / n).exp()) as f32
}

/// An equirect image of `f(direction)` at `PANO`, with the count of
/// pixels where some channel went negative (clamped to 0).
fn pano(f: impl Fn(DVec3) -> [f64; 3]) -> (HdrImage, usize) {
    let (w, h) = PANO;
    let mut negative = 0;
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h {
        for x in 0..w {
            let v = f(texel_dir(x, y, w, h, 0.0));
            if v.iter().any(|c| *c < 0.0) {
                negative += 1;
            }
            rgb.extend(v.iter().map(|c| c.max(0.0) as f32));
        }
    }
    (HdrImage { width: w, height: h, rgb }, negative)
}

/// The environment pictures; returns the files and a markdown note.
fn environment_pictures(report: &PrtReport, dir: &Path) -> Result<(Vec<PathBuf>, String)> {
    let small = downsampled(&report.environment);
    let exposure = auto_exposure(&small);
    let mut files = vec![dir.join("environment.png")];
    save(&small.tone_mapped(exposure), &files[0])?;
    let mut note = format!(
        "Environment pictures (equirect {}x{}, exposure {} for all, +Y up, Hann-windowed exact \
         projection):\n\n",
        PANO.0,
        PANO.1,
        significant(exposure as f64, 3)
    );
    for bands in [3usize, 7] {
        let sh = project_quadrature(&report.environment, &Projection { bands, ..Default::default() })?;
        let (img, neg) = pano(|d| sh.eval(d));
        let path = dir.join(format!("sh_radiance_b{bands}.png"));
        save(&img.tone_mapped(exposure), &path)?;
        let _ = writeln!(
            note,
            "- `{}`: radiance from {bands} bands; {neg} of {} pixels negative before clamping",
            path.file_name().unwrap_or_default().to_string_lossy(),
            PANO.0 * PANO.1
        );
        files.push(path);
        if bands == 3 {
            let e = sh.irradiance();
            let (img, neg) = pano(|d| e.eval(d).map(|c| c / std::f64::consts::PI));
            let path = dir.join("sh_irradiance_b3.png");
            save(&img.tone_mapped(exposure), &path)?;
            let _ = writeln!(
                note,
                "- `sh_irradiance_b3.png`: irradiance / π from 3 bands (what `--ambient sh` lights a \
                 white surface with, per normal); {neg} pixels negative"
            );
            files.push(path);
        }
    }
    Ok((files, note))
}

fn precompute_cell(r: &PrtRow) -> String {
    match r.precompute {
        None => "-".into(),
        Some(p) if p.seconds.is_nan() => "cached (no time noted)".into(),
        Some(p) => format!("{} s{}", significant(p.seconds, 3), if p.computed { "" } else { " (cache)" }),
    }
}

pub fn csv(report: &PrtReport) -> String {
    let mut s = String::from(
        "scene,env,transfer,bands,sh_samples,prt_samples,precompute_s,precompute_this_run,projection_ms,\
         composite_ms,frame_ms_median,frame_ms_p95,flip_mean,psnr\n",
    );
    for r in &report.rows {
        let m = &report.measured[r.measured];
        let (pre, this_run) = match r.precompute {
            Some(p) => (format!("{:.3}", p.seconds), p.computed.to_string()),
            None => (String::new(), String::new()),
        };
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{pre},{this_run},{:.2},{:.4},{:.4},{:.4},{:.6},{:.3}",
            report.scene.display(),
            report.env,
            r.setting.transfer,
            r.setting.bands,
            r.setting.sh_samples,
            if r.precompute.is_some() { report.prt_samples.to_string() } else { String::new() },
            r.projection_ms,
            m.pass_ms(crate::render::passes::composite::PASS.name),
            m.timing.median,
            m.timing.p95,
            r.flip_mean,
            r.psnr
        );
    }
    s
}

pub fn markdown(report: &PrtReport, pictures: &str) -> String {
    let mut s = String::new();
    let r = &report.reference;
    let _ = writeln!(s, "# PRT report: {} under {}\n", report.scene.display(), report.env);
    let _ = writeln!(
        s,
        "Device: {}. {}x{}, {} timed frames after {} warm-up per variant. {} variants ({}); PRT \
         directions {}×{} per vertex. Reference: `--reference-samples {} --reference-bounces {}` \
         (the diffuse environment light ray traced at the primary hit, {} ray(s) per path), rendered \
         in {:.0} s (its first frame's pipeline compile included); its convergence: the image at {} \
         samples against it, ꟻLIP {:.5}, PSNR {:.2} dB \
         (the two share their first samples, so this estimates the reference's own error). Exposure {} \
         (fixed, both images).\n",
        report.device,
        report.width,
        report.height,
        report.frames,
        report.warmup,
        report.rows.len(),
        if report.sweep { "one knob at a time around the base" } else { "the product of the knob values" },
        report.prt_samples,
        report.prt_samples,
        r.samples,
        r.bounces,
        r.bounces,
        report.reference_seconds,
        report.convergence.0,
        report.convergence.1,
        report.convergence.2,
        report.exposure,
    );
    s.push_str(
        "| transfer | bands | sh-samples | precompute | projection ms | composite ms \
         | frame ms (median / p95) | ꟻLIP | PSNR dB |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    let mut rows: Vec<&PrtRow> = report.rows.iter().collect();
    rows.sort_by(|a, b| a.flip_mean.total_cmp(&b.flip_mean));
    for row in rows {
        let m = &report.measured[row.measured];
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.1} | {:.3} | {:.2} / {:.2} | {:.5} | {:.2} |",
            row.setting.transfer,
            row.setting.bands,
            row.setting.sh_samples,
            precompute_cell(row),
            row.projection_ms,
            m.pass_ms(crate::render::passes::composite::PASS.name),
            m.timing.median,
            m.timing.p95,
            row.flip_mean,
            row.psnr
        );
    }
    s.push_str(
        "\n(sorted by ꟻLIP, best first; precompute: the transfer's CPU time, \"(cache)\" = loaded \
         from the disk cache in this run, the time from when it was computed.)\n\n",
    );
    for k in &report.skipped {
        let _ = writeln!(s, "- skipped: {k}");
    }
    s.push('\n');
    s.push_str(pictures);
    s.push_str(
        "\n![ꟻLIP against frame time](prt_error_vs_time.png)\n\n\
         ![ꟻLIP against precompute](prt_error_vs_precompute.png)\n",
    );
    s
}

/// One series per transfer; x from `x`, point labels "b<bands> <samples>".
fn series(report: &PrtReport, x: impl Fn(&PrtRow) -> f64) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for r in &report.rows {
        let p = (x(r), r.flip_mean, format!("b{} {}", r.setting.bands, r.setting.sh_samples));
        match out.iter_mut().find(|s| s.label == r.setting.transfer) {
            Some(s) => s.points.push(p),
            None => out.push(Series { label: r.setting.transfer.clone(), points: vec![p] }),
        }
    }
    out
}

/// Writes every output into `dir`; returns the files written.
pub fn write_all(report: &PrtReport, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let (mut files, mut pictures) = environment_pictures(report, dir)?;
    let reference = dir.join("reference.png");
    save(&report.reference_image.tone_mapped(report.exposure), &reference)?;
    files.push(reference);
    pictures.push_str("- `reference.png`: the ray-traced reference\n");
    for r in report.rows.iter().filter(|r| r.setting.bands == 3 && r.setting.sh_samples == "exact") {
        let name = format!("variant_{}.png", r.setting.transfer);
        save(&report.measured[r.measured].image.tone_mapped(report.exposure), &dir.join(&name))?;
        let map = format!("error_map_{}.png", r.setting.transfer);
        r.map.save_png(&dir.join(&map))?;
        let _ = writeln!(
            pictures,
            "- `{name}`, `{map}`: {} at 3 bands, exact projection, and its ꟻLIP map ({:.5})",
            r.setting.transfer, r.flip_mean
        );
        files.extend([dir.join(name), dir.join(map)]);
    }
    let title = format!("{}x{}: ambient error against the ray-traced reference", report.width, report.height);
    let p = dir.join("prt_error_vs_time.png");
    plot::curves(
        &p,
        &title,
        "GPU frame ms (median)",
        "ꟻLIP mean",
        &series(report, |r| report.measured[r.measured].timing.median),
    )?;
    files.push(p);
    let p = dir.join("prt_error_vs_precompute.png");
    let pre = |r: &PrtRow| r.precompute.map_or(0.0, |p| p.seconds);
    plot::curves(&p, &title, "transfer precompute s (CPU; sh: 0)", "ꟻLIP mean", &series(report, pre))?;
    files.push(p);
    let csv_path = dir.join("prt.csv");
    std::fs::write(&csv_path, csv(report)).with_context(|| format!("writing {}", csv_path.display()))?;
    files.push(csv_path);
    let md = dir.join("prt.md");
    std::fs::write(&md, markdown(report, &pictures)).with_context(|| format!("writing {}", md.display()))?;
    files.push(md);
    Ok(files)
}
