//! `report tone-sheet --maps MAP,...`: the tone operators side by side under
//! several HDR environments. Per map, one contact sheet PNG: a row per
//! operator, a column per key value (log-average auto exposure, converged),
//! plus a column at the fixed --exposure; and one table (tone_sheet.md)
//! with what auto exposure measured and the GPU ms of `luminance` and
//! `tonemap`. The scene is the report's, its environment replaced by each
//! map.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context as _, Result};
use plotters::prelude::*;

use super::knobs::Variant;
use super::measure;
use crate::app::{load_posed, RenderJob};
use crate::render::tone::{AutoExposure, ToneOperator, ToneSettings};
use crate::render::{RenderSettings, Renderer};
use crate::vk::Context;

/// The key values of the sheet's columns (Reinhard's 0.18 in the middle).
pub const KEYS: [f32; 4] = [0.09, 0.18, 0.36, 0.72];

/// One rendered cell.
struct Cell {
    image: image::RgbImage,
    /// None: the fixed-exposure column.
    key: Option<f32>,
    operator: ToneOperator,
    exposure: f32,
    log_average: f32,
    luminance_ms: f64,
    tonemap_ms: f64,
}

const LEFT: u32 = 150;
const TOP: u32 = 64;
const GAP: u32 = 4;

/// Renders the sheets of `maps` into `out`; returns the files written.
pub fn tone_sheets(
    ctx: &Context,
    job: &RenderJob,
    maps: &[PathBuf],
    warmup: usize,
    out: &Path,
) -> Result<Vec<PathBuf>> {
    anyhow::ensure!(!maps.is_empty(), "report tone-sheet: give at least one .hdr map (--maps)");
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    super::plot::register_font()?;
    let mut written = Vec::new();
    let mut md = format!(
        "# Tone operators under HDR environments\n\nScene {}, {}x{} per cell, device {}. Auto exposure: \
         log-average luminance, converged (a still frame); last column: the fixed exposure {} without \
         auto exposure. GPU ms: median of the timed frames.\n",
        job.scene.display(),
        job.width,
        job.height,
        ctx.caps.name,
        job.settings.exposure
    );
    for (m, map) in maps.iter().enumerate() {
        let (mut scene, _) = load_posed(job)?;
        let hdr = crate::scene::scene_file::load_hdr(map)
            .with_context(|| format!("report tone-sheet: map {}", map.display()))?;
        scene.environment.map = Some(hdr);
        scene.environment.map_path = Some(map.clone());
        let camera = job.camera.resolve(&scene)?;
        let mut renderer = Renderer::new(ctx, &scene, job.extent()?)?;
        let mut cells = Vec::new();
        let result: Result<()> = (|| {
            for op in ToneOperator::ALL {
                for key in KEYS.iter().map(|k| Some(*k)).chain([None]) {
                    eprintln!(
                        "tone sheet: map {}/{}, {} {}",
                        m + 1,
                        maps.len(),
                        op.name(),
                        key.map(|k| format!("key {k}")).unwrap_or("fixed exposure".into())
                    );
                    let tone = ToneSettings {
                        operator: op,
                        auto_exposure: if key.is_some() {
                            AutoExposure::LogAverage
                        } else {
                            AutoExposure::Off
                        },
                        key: key.unwrap_or(0.18),
                        ..job.settings.tone
                    };
                    let variant = Variant::new(RenderSettings { tone, ..job.settings });
                    let m =
                        measure::measure(ctx, &mut renderer, &scene, &camera, &variant, warmup, 5, false)?;
                    let state = m.exposure;
                    let (luminance_ms, tonemap_ms) = (m.pass_ms("luminance"), m.pass_ms("tonemap"));
                    cells.push(Cell {
                        image: image::RgbImage::from_raw(m.ldr.width, m.ldr.height, m.ldr.rgb)
                            .context("frame size matches its pixels")?,
                        key,
                        operator: op,
                        exposure: state.map(|s| s.exposure).unwrap_or(job.settings.exposure),
                        log_average: state.map(|s| s.log_average).unwrap_or(f32::NAN),
                        luminance_ms,
                        tonemap_ms,
                    });
                }
            }
            Ok(())
        })();
        renderer.destroy(ctx);
        result?;
        let name = map.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or(format!("map{m}"));
        let path = out.join(format!("tone_sheet_{name}.png"));
        draw_sheet(&cells, &name, &path)?;
        written.push(path.clone());
        let _ = write!(
            md,
            "\n## {name}\n\n![{name}](tone_sheet_{name}.png)\n\n| operator | key | log-average L | exposure | luminance ms | tonemap ms |\n|---|---|---|---|---|---|\n"
        );
        for c in &cells {
            let key = c.key.map(|k| k.to_string()).unwrap_or("fixed".into());
            let _ = writeln!(
                md,
                "| {} | {key} | {:.4e} | {:.4e} | {:.3} | {:.3} |",
                c.operator.name(),
                c.log_average,
                c.exposure,
                c.luminance_ms,
                c.tonemap_ms
            );
        }
    }
    let md_path = out.join("tone_sheet.md");
    std::fs::write(&md_path, md).with_context(|| format!("writing {}", md_path.display()))?;
    written.push(md_path);
    Ok(written)
}

/// Lays the cells out (rows: operators, columns: keys then fixed) with labels.
fn draw_sheet(cells: &[Cell], title: &str, path: &Path) -> Result<()> {
    let cols = KEYS.len() as u32 + 1;
    let rows = ToneOperator::ALL.len() as u32;
    let (cw, ch) = cells.first().map(|c| c.image.dimensions()).context("no cells")?;
    let (w, h) = (LEFT + cols * (cw + GAP), TOP + rows * (ch + GAP));
    let mut sheet = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    for (i, c) in cells.iter().enumerate() {
        let (r, col) = (i as u32 / cols, i as u32 % cols);
        image::imageops::replace(
            &mut sheet,
            &c.image,
            (LEFT + col * (cw + GAP)) as i64,
            (TOP + r * (ch + GAP)) as i64,
        );
    }
    let mut buf = sheet.into_raw();
    labels(&mut buf, (w, h), (cw, ch), title).map_err(|e| anyhow!("drawing {}: {e}", path.display()))?;
    image::RgbImage::from_raw(w, h, buf)
        .context("sheet buffer size")?
        .save(path)
        .with_context(|| format!("writing {}", path.display()))
}

fn labels(
    buf: &mut [u8],
    (w, h): (u32, u32),
    (cw, ch): (u32, u32),
    title: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(buf, (w, h)).into_drawing_area();
    let style = ("sans-serif", 16).into_font().color(&BLACK);
    root.draw(&Text::new(
        format!("{title}: tone operator x key (log-average auto exposure)"),
        (8, 6),
        ("sans-serif", 18).into_font(),
    ))?;
    let columns: Vec<String> =
        KEYS.iter().map(|k| format!("key {k}")).chain(["fixed exposure".to_string()]).collect();
    for (i, c) in columns.iter().enumerate() {
        let x = (LEFT + i as u32 * (cw + GAP)) as i32 + 4;
        root.draw(&Text::new(c.clone(), (x, TOP as i32 - 24), style.clone()))?;
    }
    for (r, op) in ToneOperator::ALL.iter().enumerate() {
        let y = (TOP + r as u32 * (ch + GAP) + ch / 2) as i32 - 8;
        root.draw(&Text::new(op.name().to_string(), (8, y), style.clone()))?;
    }
    root.present()?;
    Ok(())
}
