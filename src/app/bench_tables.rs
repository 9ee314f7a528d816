//! `bench`'s results: per-pass statistics, the printed tables, the CSV
//! and the paired ratios variants are compared by.

use std::path::PathBuf;

use super::BenchVariant;

/// Per-pass statistics over a benchmark run.
#[derive(Clone, Debug)]
pub struct PassStats {
    pub name: &'static str,
    pub min: f64,
    pub median: f64,
    pub p95: f64,
    pub max: f64,
}

pub struct BenchReport {
    pub scene: PathBuf,
    pub device: String,
    /// The shading variant measured (mode, backend, effects).
    pub config: String,
    pub variant: BenchVariant,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub passes: Vec<PassStats>,
    pub frame_total: PassStats,
    /// GPU ms of each measured frame, in path order.
    pub frame_totals: Vec<f64>,
    /// Camera, shadow and secondary rays of the first camera's frame.
    pub rays_first_frame: [u32; 3],
    /// NaN/Inf pixels tone mapping met, over the measured frames.
    pub bad_pixels: u64,
    /// The auto exposure of the last measured frame (None: fixed).
    pub exposure: Option<crate::render::tone::ExposureState>,
    /// Effects mode's budget: T and, per measured frame, the ray stages' predicted and measured ms.
    pub budget: Option<(f64, Vec<BudgetFrame>)>,
    /// Bytes per pixel of the G-buffer targets the run allocated.
    pub gbuffer_bytes_per_pixel: u32,
    /// G-buffer draws of the last measured frame: recorded, and left out as outside the view frustum.
    pub raster_draws: (usize, u32),
    /// Their triangles (before occlusion culling).
    pub raster_triangles: u64,
    /// Occlusion culling's counters of the last measured frame (None: off): clusters drawn in phase 1, in
    /// phase 2, occluded, outside the frustum; triangles drawn. And the scene's cluster count.
    pub occlusion: Option<([u32; 5], usize)>,
    /// Auto primary visibility: what the last measured frame used and the
    /// times it chose by (None: raster or traced was fixed, or pure RT).
    pub visibility: Option<String>,
}

impl BenchReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "scene {}  device {}  {}x{}  {} frames (GPU ms)\n{}\n{:<24} {:>9} {:>9} {:>9}\n",
            self.scene.display(),
            self.device,
            self.width,
            self.height,
            self.frames,
            self.config,
            "pass",
            "min",
            "median",
            "max"
        );
        for p in self.passes.iter().chain(std::iter::once(&self.frame_total)) {
            s.push_str(&format!("{:<24} {:>9.3} {:>9.3} {:>9.3}\n", p.name, p.min, p.median, p.max));
        }
        let [camera, shadow, secondary] = self.rays_first_frame;
        let total = (camera + shadow + secondary) as f64;
        if total > 0.0 {
            // Rays of the first frame over the median times of the passes
            // that trace them (they also shade, so this is a lower bound).
            let traced: Vec<&PassStats> =
                self.passes.iter().filter(|p| TRACING_PASSES.contains(&p.name)).collect();
            let trace_ms: f64 = traced.iter().map(|p| p.median).sum();
            s.push_str(&format!("rays/frame: camera {camera}, shadow {shadow}, secondary {secondary}"));
            if !traced.is_empty() {
                let names: Vec<_> = traced.iter().map(|p| p.name).collect();
                s.push_str(&format!(" -> {:.2} Mrays/s in {}", total / (trace_ms * 1e3), names.join(" + ")));
            }
            s.push('\n');
        }
        if let Some(p) = self.passes.iter().find(|p| p.name == crate::render::passes::path::PASS.name) {
            // The path tracer's cost per sample: a frame adds PATH_SAMPLES_PER_FRAME paths a pixel.
            let spp = crate::gpu::shared::PATH_SAMPLES_PER_FRAME as f64;
            let paths = spp * (self.width * self.height) as f64;
            s.push_str(&format!(
                "path tracer: {:.3} ms per sample per pixel ({spp} a frame), {:.3} Mpaths/s\n",
                p.median / spp,
                paths / (p.median * 1e3)
            ));
        }
        if let Some(e) = self.exposure {
            s.push_str(&format!(
                "auto exposure (last frame): log-average luminance {:.4e}, adapted {:.4e}, exposure {:.4e}\n",
                e.log_average, e.adapted, e.exposure
            ));
        }
        s.push_str(&format!("bad pixels (NaN/Inf radiance, shown magenta): {}\n", self.bad_pixels));
        s.push_str(&format!("gbuffer bytes/pixel: {}\n", self.gbuffer_bytes_per_pixel));
        let (drawn, culled) = self.raster_draws;
        if drawn + culled as usize > 0 {
            s.push_str(&format!(
                "gbuffer draws (last frame): {drawn} recorded, {culled} outside the view frustum; {} triangles\n",
                self.raster_triangles
            ));
        }
        if let Some(([first, second, occluded, outside, triangles], clusters)) = self.occlusion {
            s.push_str(&format!(
                "occlusion culling (last frame): {} of {clusters} clusters drawn ({first} in phase 1, {second} in \
                 phase 2), {occluded} occluded, {outside} outside the frustum; {triangles} triangles drawn\n",
                first + second
            ));
        }
        if let Some(v) = &self.visibility {
            s.push_str(v);
            s.push('\n');
        }
        if let Some(p) = self.passes.iter().find(|p| p.name == crate::render::passes::heuristic::PASS.name) {
            // The budget's own overhead: its statistics pass against the whole frame (medians).
            s.push_str(&format!(
                "budget heuristic: {:.3} ms, {:.1} % of the frame\n",
                p.median,
                100.0 * p.median / self.frame_total.median
            ));
        }
        if let Some((t, frames)) = &self.budget {
            s.push_str(&budget_table(*t, frames));
        }
        s
    }
}

/// One frame of effects mode's budget: the ray stages' (`direct` +
/// `specular`) predicted and measured ms and rays.
#[derive(Clone, Copy, Debug)]
pub struct BudgetFrame {
    pub predicted_ms: f64,
    pub measured_ms: f64,
    pub predicted_rays: f64,
    pub measured_rays: f64,
}

/// Effects mode's budget against what the ray stages took, per frame. The rays tell a wrong ray estimate (the
/// selection's latency on a moving camera) from a wrong or noisy time per ray.
fn budget_table(t: f64, frames: &[BudgetFrame]) -> String {
    let mut s = format!(
        "budget T = {t:.3} ms (effects mode), ray stages (direct + specular + glossy) and shadow maps per frame:\n"
    );
    s.push_str(&format!(
        "{:>6} {:>11} {:>10} {:>8} {:>12} {:>12}\n",
        "frame", "predicted", "measured", "vs T", "pred. rays", "rays"
    ));
    for (i, f) in frames.iter().enumerate() {
        s.push_str(&format!(
            "{i:>6} {:>11.3} {:>10.3} {:>+7.1}% {:>12.0} {:>12.0}\n",
            f.predicted_ms,
            f.measured_ms,
            (f.measured_ms / t - 1.0) * 100.0,
            f.predicted_rays,
            f.measured_rays
        ));
    }
    let within = frames.iter().filter(|f| (f.measured_ms / t - 1.0).abs() <= 0.1).count();
    let m = stats("ray stages", frames.iter().map(|f| f.measured_ms).collect());
    s.push_str(&format!(
        "within +-10% of T: {within} of {} frames; measured median {:.3} ms, p95 {:.3} ms",
        frames.len(),
        m.median,
        m.p95
    ));
    if frames.iter().all(|f| f.predicted_ms < 0.9 * t) {
        s.push_str(" (T is more than tracing every effect of every visible object costs)");
    } else if frames.iter().all(|f| f.predicted_rays == 0.0 && f.predicted_ms > 1.1 * t) {
        s.push_str(" (T is below what the ray stages cost tracing nothing: no selection can meet it)");
    }
    s.push('\n');
    s
}

/// The passes that may trace rays (camera, shadow, reflection/refraction).
const TRACING_PASSES: [&str; 7] =
    ["primary", "visibility trace", "direct", "reference", "specular", "glossy", "path"];

pub(super) fn stats(name: &'static str, mut v: Vec<f64>) -> PassStats {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len().max(1);
    PassStats {
        name,
        min: v.first().copied().unwrap_or(f64::NAN),
        median: v.get(n / 2).copied().unwrap_or(f64::NAN),
        p95: v.get(((0.95 * n as f64).ceil() as usize).clamp(1, n) - 1).copied().unwrap_or(f64::NAN),
        max: v.last().copied().unwrap_or(f64::NAN),
    }
}

/// Per-frame ratios of frame times `r` to `base` (same path position, rendered next to each other): [first
/// quartile, median, third quartile]. None where the runs differ in length or a base frame took no time.
pub fn paired_ratios(r: &[f64], base: &[f64]) -> Option<[f64; 3]> {
    if r.len() != base.len() || r.is_empty() {
        return None;
    }
    let mut q: Vec<f64> = r.iter().zip(base).map(|(a, b)| a / b).collect();
    if q.iter().any(|x| !x.is_finite()) {
        return None;
    }
    q.sort_by(f64::total_cmp);
    let at = |p: f64| {
        // Linear interpolation between order statistics.
        let x = p * (q.len() - 1) as f64;
        let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
        q[lo] + (q[hi] - q[lo]) * (x - lo as f64)
    };
    Some([at(0.25), at(0.5), at(0.75)])
}

/// The tables of `reports` as CSV: one row per variant and pass (the frame total last), GPU ms.
pub fn bench_csv(reports: &[BenchReport]) -> String {
    use crate::csv::{csv_field, csv_number};
    let mut s = String::from(
        "variant,mode,backend,accel_update,config,pass,ms_min,ms_median,ms_p95,ms_max,frames,width,height,\
         rays_camera,rays_shadow,rays_secondary\n",
    );
    for (i, r) in reports.iter().enumerate() {
        let v = &r.variant;
        for p in r.passes.iter().chain(std::iter::once(&r.frame_total)) {
            let [c, sh, sec] = r.rays_first_frame;
            let row = [
                (i + 1).to_string(),
                format!("{:?}", v.mode).to_lowercase(),
                format!("{:?}", v.backend).to_lowercase(),
                format!("{:?}", v.accel).to_lowercase(),
                csv_field(&r.config),
                csv_field(p.name),
                csv_number(p.min, 4),
                csv_number(p.median, 4),
                csv_number(p.p95, 4),
                csv_number(p.max, 4),
                r.frames.to_string(),
                r.width.to_string(),
                r.height.to_string(),
                c.to_string(),
                sh.to_string(),
                sec.to_string(),
            ];
            s.push_str(&row.join(","));
            s.push('\n');
        }
    }
    s
}

/// "slower" / "faster" for a time ratio against the baseline.
pub fn ratio_word(ratio: f64) -> &'static str {
    if (ratio - 1.0).abs() < 0.005 {
        "as fast"
    } else if ratio > 1.0 {
        "slower"
    } else {
        "faster"
    }
}

#[cfg(test)]
mod tests {
    use super::{budget_table, paired_ratios, BudgetFrame};

    #[test]
    fn the_budget_table_says_when_t_is_out_of_reach() {
        let frame = |predicted_ms, measured_ms, rays| BudgetFrame {
            predicted_ms,
            measured_ms,
            predicted_rays: rays,
            measured_rays: rays,
        };
        let below = budget_table(20.0, &[frame(190.0, 200.0, 0.0), frame(180.0, 170.0, 0.0)]);
        assert!(
            below.contains("within +-10% of T: 0 of 2") && below.contains("no selection can meet it"),
            "{below}"
        );
        let above = budget_table(20.0, &[frame(10.0, 11.0, 50.0)]);
        assert!(above.contains("more than tracing every effect"), "{above}");
        let met = budget_table(20.0, &[frame(20.0, 21.0, 50.0), frame(20.0, 19.0, 0.0)]);
        assert!(met.contains("2 of 2") && !met.contains("(T is"), "{met}");
    }

    #[test]
    fn paired_ratios_pair_frames_by_position() {
        // A drift that doubles both variants' times cancels frame by frame:
        // the ratio of the medians would read 1.5 here, the pairs read 0.5.
        let base = [10.0, 20.0, 40.0, 80.0, 160.0];
        let r = [5.0, 10.0, 20.0, 40.0, 80.0];
        assert_eq!(paired_ratios(&r, &base), Some([0.5, 0.5, 0.5]));
        // Quartiles interpolate between the sorted ratios (1, 2, 3, 4, 5).
        let r = [10.0, 60.0, 80.0, 320.0, 800.0];
        assert_eq!(paired_ratios(&r, &base), Some([2.0, 3.0, 4.0]));
        assert_eq!(paired_ratios(&[1.0, 2.0], &[2.0, 4.0]), Some([0.5, 0.5, 0.5]));
        assert_eq!(paired_ratios(&[1.0, 2.0, 3.0], &[1.0, 1.0, 1.0]), Some([1.5, 2.0, 2.5]));
        // Unpaired or degenerate runs give no ratio.
        assert_eq!(paired_ratios(&[1.0], &[1.0, 2.0]), None);
        assert_eq!(paired_ratios(&[], &[]), None);
        assert_eq!(paired_ratios(&[1.0], &[0.0]), None);
    }
}
