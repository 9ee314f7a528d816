//! The default hybrid frame against the path-traced truth, per object, and an attribution of its
//! error: how much goes away when one term the hybrid approximates or leaves out comes from the path
//! tracer instead (pass `terms`): rough environment reflection, diffuse environment with visibility,
//! one indirect bounce, emissive surfaces, caustics. Each term is accumulated like the truth (its two
//! halves give its noise); "every term" replaces all, leaving what none models (further bounces,
//! glossy reflections seen as mirrors, edge filtering, ...).

use anyhow::{bail, Context as _, Result};

use super::metrics::{self, FlipMap, HdrImage};
use crate::gpu::shared::{
    TERMS_SAMPLES_PER_FRAME, TERM_CAUSTICS, TERM_EMITTERS, TERM_ENV_SPECULAR, TERM_INDIRECT, TERM_VISIBILITY,
};
use crate::render::{DebugView, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
use crate::vk::Context;

/// One term the attribution can supply: its `TERM_*` bit, its name in the
/// report, and what the hybrid frame does in its place.
pub struct Term {
    pub bit: u32,
    pub name: &'static str,
    pub hybrid: &'static str,
}

pub const TERMS: [Term; 5] = [
    Term {
        bit: TERM_ENV_SPECULAR,
        name: "environment specular",
        hybrid:
            "the split-sum prefiltered environment (--ambient traced: times the specular occlusion of its \
                 visibility where no glossy ray corrects it; mirrors: traced)",
    },
    Term {
        bit: TERM_VISIBILITY,
        name: "diffuse visibility",
        hybrid:
            "--ambient traced: the SH ambient times the traced visible share; else the unshadowed SH (or \
                 PRT) ambient",
    },
    Term {
        bit: TERM_INDIRECT,
        name: "one indirect bounce",
        hybrid: "--ambient traced: its rays' hits lit by the punctual lights and the emitters; else none",
    },
    Term {
        bit: TERM_EMITTERS,
        name: "emissive surfaces",
        hybrid:
            "--ambient traced: light samples on the emissive triangles (diffuse and untraced rough \
                 specular lobes) with its rays that hit them, MIS-weighted; else none (emission is only seen)",
    },
    Term {
        bit: TERM_CAUSTICS,
        name: "caustics",
        hybrid: "direct light through glass by its transmittance, straight",
    },
];

/// The bits of every term.
pub fn all_terms() -> u32 {
    TERMS.iter().fold(0, |a, t| a | t.bit)
}

/// The hybrid frame with `terms` supplied, against the truth.
pub struct TermRow {
    /// A term's name, or "every term".
    pub name: String,
    pub terms: u32,
    pub flip_mean: f64,
    pub psnr: f64,
    /// Its two halves against each other (its own noise is about half this).
    pub halves_flip: f64,
    pub map: FlipMap,
}

impl TermRow {
    /// Its own distance to its limit, estimated as the truth's
    /// (truth.rs): half what its two halves differ by.
    pub fn noise(&self) -> f64 {
        self.halves_flip / 2.0
    }
}

/// One object's pixels (primary hits) in the default frame and the truth.
pub struct ObjectRow {
    /// The scene's object name ("(environment)": no primary hit).
    pub name: String,
    pub pixels: usize,
    /// Mean luminance of the hybrid frame and of the truth over the pixels.
    pub hybrid: f64,
    pub truth: f64,
    /// Mean ꟻLIP over the pixels: the default frame, every term supplied.
    pub flip: f64,
    pub flip_all: f64,
    /// Per term (TERMS order): mean ꟻLIP over the pixels with that term supplied.
    pub flip_terms: Vec<f64>,
}

pub struct Attribution {
    /// Samples per pixel of each term's estimate.
    pub samples: u32,
    /// The default frame against the truth.
    pub base_flip: f64,
    pub base_psnr: f64,
    pub rows: Vec<TermRow>,
    pub objects: Vec<ObjectRow>,
}

impl Attribution {
    /// The term whose row removes most of an object's error, and how much.
    pub fn best_term(&self, o: &ObjectRow) -> Option<(&'static str, f64)> {
        let gains = TERMS.iter().zip(&o.flip_terms).map(|(t, f)| (t.name, o.flip - f));
        gains.max_by(|a, b| a.1.total_cmp(&b.1)).filter(|(_, g)| *g > 0.0)
    }
}

/// Objects covering fewer pixels than this are left out of the table.
const MIN_OBJECT_PIXELS: usize = 16;

fn luminance(p: &[f32]) -> f64 {
    (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64
}

/// Renders `settings` with `terms` supplied for `samples` samples per pixel
/// (two halves); returns the image and its halves.
fn with_terms(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    terms: u32,
    samples: u32,
) -> Result<(HdrImage, HdrImage, HdrImage)> {
    let half = samples.div_ceil(2 * TERMS_SAMPLES_PER_FRAME).max(1);
    let settings = RenderSettings { terms, ..*settings };
    renderer.reset_reference();
    let mut first = None;
    let mut out = None;
    for i in 0..2 * half {
        let o = renderer.render(ctx, scene, camera, &settings)?;
        if i + 1 == half {
            first = Some(o.hdr.clone());
        }
        out = Some(o);
    }
    let out = out.context("no frame rendered")?;
    if renderer.reference_frames() != 2 * half {
        bail!("the attribution's accumulation restarted part-way ({} frames)", renderer.reference_frames());
    }
    let first = first.context("no half-way frame")?;
    let h = super::truth::Halves::of(out.width, out.height, &out.hdr, &first);
    Ok((h.full, h.first, h.second))
}

/// The attribution of `base`, the frame `settings` renders (the report's
/// base hybrid settings, already measured), against `truth`, each term
/// with `samples` samples.
#[allow(clippy::too_many_arguments)]
pub fn run(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    base: &HdrImage,
    truth: &HdrImage,
    exposure: f32,
    samples: u32,
) -> Result<Attribution> {
    let plain = RenderSettings { terms: 0, reference: None, ..*settings };
    let ids =
        renderer.render(ctx, scene, camera, &RenderSettings { debug_view: DebugView::ObjectId, ..plain })?;
    if (base.width, base.height) != (truth.width, truth.height) {
        bail!(
            "the attribution's frame is {}x{}, the truth {}x{}",
            base.width,
            base.height,
            truth.width,
            truth.height
        );
    }
    let truth_ldr = truth.tone_mapped(exposure);
    let base_map = metrics::flip(&truth_ldr, &base.tone_mapped(exposure))?;
    let mut rows = Vec::new();
    let started = std::time::Instant::now();
    let configs: Vec<(String, u32)> = TERMS
        .iter()
        .map(|t| (t.name.to_string(), t.bit))
        .chain([("every term".to_string(), all_terms())])
        .collect();
    for (i, (name, bits)) in configs.iter().enumerate() {
        eprintln!(
            "report: attribution [{}/{}] {name} supplied by the path tracer ({samples} samples, {:.0} s so far)",
            i + 1,
            configs.len(),
            started.elapsed().as_secs_f64()
        );
        let (image, a, b) = with_terms(ctx, renderer, scene, camera, &plain, *bits, samples)
            .with_context(|| format!("report: the attribution's term {name}"))?;
        let e = metrics::compare_hdr(truth, &image, exposure)?;
        let halves = metrics::compare_hdr(&a, &b, exposure)?;
        rows.push(TermRow {
            name: name.clone(),
            terms: *bits,
            flip_mean: e.flip_mean,
            psnr: e.psnr,
            halves_flip: halves.flip_mean,
            map: e.map,
        });
    }
    let objects = per_object(scene, &ids.hdr, base, truth, &base_map, &rows);
    Ok(Attribution {
        samples: 2 * samples.div_ceil(2 * TERMS_SAMPLES_PER_FRAME).max(1) * TERMS_SAMPLES_PER_FRAME,
        base_flip: base_map.mean(),
        base_psnr: metrics::psnr_hdr(truth, base),
        rows,
        objects,
    })
}

/// Per object id (the ObjectId debug view's radiance, RGBA: index + 1, 0
/// for the environment): its pixels' statistics, largest first.
fn per_object(
    scene: &Scene,
    ids: &[f32],
    base: &HdrImage,
    truth: &HdrImage,
    base_map: &FlipMap,
    rows: &[TermRow],
) -> Vec<ObjectRow> {
    let mut by_id: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
    for (i, p) in ids.chunks_exact(4).enumerate() {
        by_id.entry(p[0].max(0.0).round() as u32).or_default().push(i);
    }
    let mean = |pixels: &[usize], f: &dyn Fn(usize) -> f64| {
        pixels.iter().map(|&i| f(i)).sum::<f64>() / pixels.len() as f64
    };
    let all = rows.iter().find(|r| r.terms == all_terms());
    let mut objects: Vec<ObjectRow> = by_id
        .into_iter()
        .filter(|(_, px)| px.len() >= MIN_OBJECT_PIXELS)
        .map(|(id, px)| {
            let name = match id {
                0 => "(environment)".to_string(),
                _ => scene
                    .objects
                    .get(id as usize - 1)
                    .map_or(format!("object {}", id - 1), |o| o.name.clone()),
            };
            let flip_of = |m: &FlipMap| mean(&px, &|i| m.values[i] as f64);
            ObjectRow {
                name,
                pixels: px.len(),
                hybrid: mean(&px, &|i| luminance(&base.rgb[3 * i..3 * i + 3])),
                truth: mean(&px, &|i| luminance(&truth.rgb[3 * i..3 * i + 3])),
                flip: flip_of(base_map),
                flip_all: all.map_or(f64::NAN, |r| flip_of(&r.map)),
                flip_terms: TERMS
                    .iter()
                    .map(|t| rows.iter().find(|r| r.terms == t.bit).map_or(f64::NAN, |r| flip_of(&r.map)))
                    .collect(),
            }
        })
        .collect();
    objects.sort_by_key(|o| std::cmp::Reverse(o.pixels));
    objects
}

impl Attribution {
    /// report.md's section.
    pub fn markdown(&self, base_config: &str) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(s, "## The default frame's error, per object and per missing term\n");
        let _ = writeln!(
            s,
            "The base settings' hybrid frame ({base_config}) against the truth: **ꟻLIP {:.5}**, PSNR {} dB. \
             Each row supplies one term of light transport from the path tracer instead of the hybrid's \
             approximation (pass `terms`: at the primary hit, {} samples per pixel of the path tracer's BSDF; \
             README, \"Report\") and measures the frame again: the drop is the error that term is responsible \
             for. A term's own noise is about half its halves' ꟻLIP; a drop smaller than that is marked \
             (within noise): raise --attribution-samples to resolve it.\n",
            self.base_flip,
            super::write::db(self.base_psnr),
            self.samples
        );
        let _ = writeln!(s, "| term supplied by the path tracer | the hybrid frame instead | ꟻLIP | drop | PSNR (dB) | halves' ꟻLIP |");
        let _ = writeln!(s, "|---|---|---|---|---|---|");
        let _ = writeln!(
            s,
            "| none (the default frame) | | {:.5} | | {} | |",
            self.base_flip,
            super::write::db(self.base_psnr)
        );
        for r in &self.rows {
            let hybrid = TERMS.iter().find(|t| t.bit == r.terms).map_or("all of the above", |t| t.hybrid);
            let drop = r.flip_mean - self.base_flip;
            let noise = if drop.abs() < r.noise() { " (within noise)" } else { "" };
            let _ = writeln!(
                s,
                "| {} | {hybrid} | {:.5} | {drop:+.5}{noise} | {} | {:.5} |",
                r.name,
                r.flip_mean,
                super::write::db(r.psnr),
                r.halves_flip
            );
        }
        let _ = writeln!(
            s,
            "\nEach term is a set of the truth's own paths. What is left with every term supplied is what \
             none of them holds: the environment's light after a bounce, two or more rough bounces, glossy \
             surfaces the hybrid traces as mirrors, the truth's pixel filtering at edges.\n"
        );
        let _ = writeln!(
            s,
            "Per object (primary hits; at least {MIN_OBJECT_PIXELS} pixels), largest first: mean luminance of \
             the frame over the truth's, mean ꟻLIP, with every term supplied, and the term whose supply \
             lowers it most.\n"
        );
        let _ =
            writeln!(s, "| object | pixels | hybrid / truth luminance | ꟻLIP | every term | largest drop |");
        let _ = writeln!(s, "|---|---|---|---|---|---|");
        for o in &self.objects {
            let ratio = if o.truth > 0.0 { format!("{:.3}", o.hybrid / o.truth) } else { "-".into() };
            let best = self.best_term(o).map_or("none".into(), |(n, g)| format!("{n} ({:+.5})", -g));
            let _ = writeln!(
                s,
                "| {} | {} | {ratio} | {:.5} | {:.5} | {best} |",
                o.name.replace('|', "\\|"),
                o.pixels,
                o.flip,
                o.flip_all
            );
        }
        s.push('\n');
        s
    }

    /// attribution.csv: the default frame, a row per term, then a row per object.
    pub fn csv(&self) -> String {
        use crate::csv::{csv_field, csv_number};
        let n = |v: f64| csv_number(v, 6);
        let mut header: Vec<String> =
            ["kind", "name", "pixels", "hybrid_luminance", "truth_luminance", "flip_mean", "flip_every_term"]
                .map(String::from)
                .to_vec();
        header.extend(TERMS.iter().map(|t| format!("flip_{}", t.name.replace(' ', "_"))));
        header.push("halves_flip".into());
        let line = |mut fields: Vec<String>| {
            fields.resize(header.len(), String::new());
            fields.join(",") + "\n"
        };
        let mut s = header.join(",") + "\n";
        s += &line(vec![
            "frame".into(),
            "default".into(),
            String::new(),
            String::new(),
            String::new(),
            n(self.base_flip),
        ]);
        for r in &self.rows {
            let mut f = vec![
                "term".into(),
                csv_field(&r.name),
                String::new(),
                String::new(),
                String::new(),
                n(r.flip_mean),
            ];
            f.resize(header.len() - 1, String::new());
            f.push(n(r.halves_flip));
            s += &line(f);
        }
        for o in &self.objects {
            let mut f = vec![
                "object".into(),
                csv_field(&o.name),
                o.pixels.to_string(),
                n(o.hybrid),
                n(o.truth),
                n(o.flip),
                n(o.flip_all),
            ];
            f.extend(o.flip_terms.iter().map(|v| n(*v)));
            s += &line(f);
        }
        s
    }
}
