//! The report's tables: `report.md` for people, `report.csv` for tools
//! (one row per knob setting; the first seven columns are fixed, later
//! ones may be added after them).

use std::fmt::Write as _;

use super::{Report, Row};
use crate::csv::{csv_field, csv_number};
use crate::render::shading::Mode;

/// The fixed leading columns of report.csv.
pub const CSV_HEADER: &str = "knob,value,backend,ms_median,ms_p95,flip_mean,psnr";
/// Columns after the fixed ones.
const CSV_EXTRA: &str =
    "rel_mse,width,height,rays_camera,rays_shadow,rays_secondary,non_finite_pixels,aa_pass_ms";

pub fn csv(report: &Report) -> String {
    let mut s = format!("{CSV_HEADER},{CSV_EXTRA}\n");
    for row in &report.rows {
        let m = &report.measured[row.measured];
        let rays: Vec<String> = match m.rays {
            Some(r) => r.iter().map(|v| v.to_string()).collect(),
            None => vec![String::new(); 3],
        };
        let fields = [
            csv_field(row.knob),
            csv_field(&row.value),
            csv_field(&m.backend),
            csv_number(m.timing.median, 4),
            csv_number(m.timing.p95, 4),
            csv_number(row.flip_mean, 6),
            csv_number(row.psnr, 3),
            csv_number(row.rel_mse, 6),
            m.width.to_string(),
            m.height.to_string(),
            rays.join(","),
            m.non_finite.to_string(),
            m.timing.aa_pass().map(|ms| csv_number(ms, 4)).unwrap_or_default(),
        ];
        s.push_str(&fields.join(","));
        s.push('\n');
    }
    s
}

/// The error map file of a row: `error_map_<knob>_<value>.png`, the value
/// kept to file-name-safe characters ('+' spelled "plus").
pub fn error_map_name(row: &Row) -> String {
    let value: String = row
        .value
        .replace('+', "plus-")
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '-' { c } else { '_' })
        .collect();
    format!("error_map_{}_{value}.png", row.knob)
}

pub fn db(v: f64) -> String {
    if v.is_infinite() {
        "∞".into()
    } else {
        format!("{v:.2}")
    }
}

fn rays(r: Option<[u32; 3]>) -> String {
    match r {
        Some([c, s, x]) => format!("{} ({c} / {s} / {x})", c as u64 + s as u64 + x as u64),
        None => "not counted".into(),
    }
}

/// `report.md`; `maps` are the error maps written (knob, value, file).
pub fn markdown(report: &Report, maps: &[(&'static str, String, String)]) -> String {
    let mut s = String::new();
    let r = report.reference();
    let rs = &report.reference_settings;
    let _ = writeln!(s, "# Image error against GPU time: {}\n", report.scene.display());
    let _ = writeln!(
        s,
        "Device {}, {}x{}, {} timed frames per setting after {} warm-up frame(s), every setting \
         in one process run.\n",
        report.device, report.width, report.height, report.frames, report.warmup
    );
    let _ = writeln!(s, "## Reference\n");
    if let Some(t) = &report.truth {
        let smallest = report
            .rows
            .iter()
            .filter(|r| r.knob != "aa" && r.flip_mean > 0.0)
            .map(|r| r.flip_mean)
            .fold(f64::INFINITY, f64::min);
        let _ = writeln!(
            s,
            "The path-traced ground truth (`--ref path`; README, \"Path-traced ground truth\"): {} paths per \
             pixel, backend {}, exposure {} ({}), {}. Every row below is its distance from the true image, \
             approximations shared by every setting included. `reference.png` is its tone-mapped image.\n",
            t.samples,
            r.backend,
            report.reference_exposure,
            r.config,
            if t.cached {
                "read from the cache (`--no-ref-cache` renders it again)".to_string()
            } else {
                format!("rendered in {:.1} s", t.seconds)
            }
        );
        let verdict = if t.noise() <= 0.5 * smallest {
            format!("under half the smallest error measured ({smallest:.5})")
        } else {
            format!(
                "**not** under half the smallest error measured ({smallest:.5}): rows that close to it are within \
                 the reference's noise (raise --ref-max-samples)"
            )
        };
        let _ = writeln!(
            s,
            "Its own noise: the first and second halves of its samples differ by ꟻLIP {:.5} (PSNR {} dB), so the \
             whole is about ꟻLIP {:.5} from its limit, {verdict}.\n",
            t.halves_flip,
            db(t.halves_psnr),
            t.noise()
        );
    } else {
        let _ = writeln!(
            s,
            "The same renderer at its most accurate affordable settings: {}, every effect on, max \
         depth {}, min weight {}, backend {}, exposure {} ({}). It took {:.3} ms per frame \
         (median). `reference.png` is its tone-mapped image.\n",
            match rs.mode {
                Mode::Rt => "pure-RT mode (camera rays traced)",
                Mode::Path => "the path tracer",
                Mode::Hybrid =>
                    "hybrid mode (G-buffer primary hits; chosen with --ref-mode hybrid, so the \
                             rows leave out the hybrid-vs-rt difference below)",
            },
            rs.max_depth,
            rs.min_weight,
            r.backend,
            report.reference_exposure,
            r.config,
            r.timing.median
        );
        let c = &report.convergence;
        let _ = writeln!(
            s,
            "Convergence: {}: ꟻLIP {:.5}, PSNR {} dB; tone-mapped: {} (the smaller, the closer the reference \
             is to converged).\n",
            c.about,
            c.flip_mean,
            db(c.psnr),
            c.ldr.describe()
        );
    }
    let k = &report.self_check;
    let _ = writeln!(s, "## Self-check: hybrid vs rt at equal settings\n");
    let _ = writeln!(
        s,
        "**ꟻLIP {:.5}, PSNR {} dB** — {}; tone-mapped: {}. The G-buffer is the primary hit, so the two \
         should be (near-)identical. (LDR-ꟻLIP is not blind to one-level 8-bit differences: on \
         flat areas they score about 0.02-0.03.)\n",
        k.flip_mean,
        db(k.psnr),
        k.about,
        k.ldr.describe()
    );
    let _ = writeln!(s, "## How it is measured\n");
    let _ = writeln!(
        s,
        "- Time: GPU timestamps of each pass, summed per frame (readback excluded); median and \
         p95 over the timed frames. Each setting's pipelines are compiled and warmed before it \
         is timed.\n\
         - ꟻLIP: NVIDIA's reference implementation (`nv-flip`), LDR-ꟻLIP at 67 pixels per \
         degree on both images tone-mapped by this renderer's tone mapper with the reference's \
         exposure ({}), frozen; the mean of the per-pixel error.\n\
         - PSNR: linear radiance, peak = the reference's largest channel value; relMSE: mean of \
         (x - ref)^2 / (ref^2 + 0.01).\n\
         - resolution-scale: rendered at the scaled size, resampled bilinearly (linear radiance) \
         to the reference's size, then compared.\n\
         - rays/frame: total (camera / shadow / secondary) of one counted frame.\n",
        report.reference_exposure
    );
    if let Some(aa) = &report.aa_reference {
        let k = aa.supersample.factor;
        let _ = writeln!(
            s,
            "- aa: anti-aliasing runs after tone mapping and changes no radiance, so these rows \
             compare the final 8-bit images (LDR-ꟻLIP, 8-bit PSNR; no relMSE) with the base \
             settings rendered {k}x{k} supersampled ({}x{} samples, {:?} filter, filtered as \
             linear display values) at the base exposure, frozen ({:.0} ms per frame for the \
             large frame).\n",
            report.width * k,
            report.height * k,
            aa.supersample.filter,
            aa.ms
        );
    }
    let mut knob_order: Vec<&'static str> = Vec::new();
    for row in &report.rows {
        if !knob_order.contains(&row.knob) {
            knob_order.push(row.knob);
        }
    }
    for knob in &knob_order {
        let about = super::knobs::find(knob).map(|k| k.about).unwrap_or("");
        let _ = writeln!(s, "## {knob}\n\n{about}.\n");
        if *knob == "aa" {
            // The filter's own cost next to what it buys.
            let cells: Vec<String> = report
                .rows
                .iter()
                .filter(|r| r.knob == "aa")
                .map(|r| match report.measured[r.measured].timing.aa_pass() {
                    Some(ms) => format!("{} {ms:.3} ms", r.value),
                    None => format!("{} no pass", r.value),
                })
                .collect();
            let _ = writeln!(
                s,
                "Against the supersampled base, not the reference (see \"How it is measured\"), so plotted \
                 apart, in `{}`. AA pass (median GPU ms): {}.\n",
                super::AA_PLOT,
                cells.join(", ")
            );
        }
        let _ = writeln!(
            s,
            "| knob | value | backend | ms median | ms p95 | ꟻLIP mean | PSNR (dB) | relMSE | rays/frame |"
        );
        let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---:|---|");
        for row in report.rows.iter().filter(|r| r.knob == *knob) {
            let m = &report.measured[row.measured];
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.3} | {:.3} | {:.5} | {} | {} | {} |",
                row.knob,
                row.value,
                m.backend,
                m.timing.median,
                m.timing.p95,
                row.flip_mean,
                db(row.psnr),
                // (The aa rows compare 8-bit images: no radiance error.)
                if row.rel_mse.is_nan() { "-".to_string() } else { format!("{:.5}", row.rel_mse) },
                rays(m.rays)
            );
        }
        s.push('\n');
    }
    if let Some(a) = &report.attribution {
        s += &a.markdown(&report.measured[report.base].config);
    }
    // Per-pass breakdown: one column per pass any setting ran.
    let mut passes: Vec<&'static str> = Vec::new();
    for m in &report.measured {
        for (p, _) in &m.timing.passes {
            if !passes.contains(p) {
                passes.push(p);
            }
        }
    }
    let _ = writeln!(s, "## Per-pass median GPU ms\n");
    let _ = writeln!(s, "| knob | value | {} |", passes.join(" | "));
    let _ = writeln!(s, "|---|---|{}", "---:|".repeat(passes.len()));
    let per_pass = |m: &super::Measured| -> String {
        let cells: Vec<String> = passes
            .iter()
            .map(|p| m.timing.pass(p).map(|ms| format!("{ms:.3}")).unwrap_or_else(|| "-".into()))
            .collect();
        cells.join(" | ")
    };
    let _ = writeln!(s, "| reference | | {} |", per_pass(r));
    for row in &report.rows {
        let _ =
            writeln!(s, "| {} | {} | {} |", row.knob, row.value, per_pass(&report.measured[row.measured]));
    }
    let _ = writeln!(s, "\n## Files\n");
    let _ = writeln!(
        s,
        "- `error_vs_time.png`: ꟻLIP mean against median GPU ms (log scale), one series per knob; \
         the black line joins the Pareto front (no other setting is both faster and closer to \
         the reference). Lower and further left is better. The aa knob's rows, measured against the \
         supersampled base instead, are not in it: `{}` shows them.",
        super::AA_PLOT
    );
    let _ = writeln!(s, "- `report.csv`: these rows, columns `{CSV_HEADER},{CSV_EXTRA}`.");
    if report.attribution.is_some() {
        let _ = writeln!(s, "- `attribution.csv`: the default frame's error per term and per object.");
    }
    for (knob, value, file) in maps {
        let _ = writeln!(s, "- `{file}`: per-pixel ꟻLIP error of the worst {knob} setting ({value}).");
    }
    if !report.skipped.is_empty() {
        let _ = writeln!(s, "\n## Not measured\n");
        for why in &report.skipped {
            let _ = writeln!(s, "- {why}");
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fixed_columns_stay_seven() {
        assert_eq!(CSV_HEADER.split(',').count(), 7);
    }
}
