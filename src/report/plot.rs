//! `error_vs_time.png`: ꟻLIP mean against median GPU frame ms (log axis),
//! one series per knob, the Pareto front over all settings marked; and
//! [`curves`], a plain line chart of labelled series. Drawn
//! with `plotters` into a buffer saved by `image`; text through ab_glyph
//! from a TTF file (DejaVu Sans, Debian's fonts-dejavu-core).

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context as _, Result};
use plotters::prelude::*;

use super::{Report, Row};

/// Indices of the points (ms, error) on the Pareto front: no other point
/// is at most as slow and at most as wrong while better in one of the two.
/// Sorted by time. Non-finite points are never on it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> =
        (0..points.len()).filter(|&i| points[i].0.is_finite() && points[i].1.is_finite()).collect();
    order.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0).then(points[a].1.total_cmp(&points[b].1)));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// Where the plot's font is looked for: $HYBRID_RT_FONT, then the
/// fonts-dejavu-core file (installed by .ci/setup-debian.sh).
fn font_candidates() -> Vec<PathBuf> {
    let mut c: Vec<PathBuf> = std::env::var_os("HYBRID_RT_FONT").map(PathBuf::from).into_iter().collect();
    c.push(PathBuf::from("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"));
    c
}

/// Registers the TTF font for plotters' "sans-serif" family, once.
pub(super) fn register_font() -> Result<()> {
    static REGISTERED: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let candidates = font_candidates();
            let Some(path) = candidates.iter().find(|p| p.is_file()) else {
                let looked: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
                return Err(format!(
                    "no font for the plot's labels (looked at {}); install fonts-dejavu-core \
                     (bash .ci/setup-debian.sh) or set HYBRID_RT_FONT to a .ttf file",
                    looked.join(", ")
                ));
            };
            let bytes = std::fs::read(path).map_err(|e| format!("reading {}: {e}", path.display()))?;
            // plotters keeps fonts for the whole process.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
                .map_err(|_| format!("{} is not a usable TrueType font", path.display()))
        })
        .clone()
        .map_err(|e| anyhow!(e))
}

/// ColorBrewer Set1 without its yellow (unreadable on white), then grey.
const SERIES_COLORS: [(u8, u8, u8); 8] = [
    (228, 26, 28),
    (55, 126, 184),
    (77, 175, 74),
    (152, 78, 163),
    (255, 127, 0),
    (166, 86, 40),
    (247, 129, 191),
    (102, 102, 102),
];

const W: u32 = 1200;
const H: u32 = 760;

/// The rows one chart shows: the `aa` knob's (measured against the
/// supersampled base, `aa`) or every other knob's (against the report's
/// reference): errors against different references share no axis.
pub fn plotted_rows(report: &Report, aa: bool) -> Vec<&Row> {
    report.rows.iter().filter(|r| (r.knob == "aa") == aa).collect()
}

/// Draws the chart of `report`'s rows against its reference (`aa` false)
/// or of the `aa` rows against their own (true) to `path` (PNG).
pub fn error_vs_time(report: &Report, path: &Path, aa: bool) -> Result<()> {
    register_font()?;
    let rows = plotted_rows(report, aa);
    let points: Vec<(f64, f64)> =
        rows.iter().map(|r| (report.measured[r.measured].timing.median, r.flip_mean)).collect();
    let finite: Vec<&(f64, f64)> = points.iter().filter(|p| p.0.is_finite() && p.0 > 0.0).collect();
    let (lo, hi) = finite.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
    // The log axis puts its ticks from the first power of ten in range on:
    // reach down to one when the data spans none.
    let (lo, hi) = if finite.is_empty() {
        (0.1, 10.0)
    } else {
        let (lo, hi) = (lo / 1.2, hi * 1.2);
        let decade = 10f64.powf(lo.log10().ceil());
        (if decade <= hi { lo } else { 10f64.powf(lo.log10().floor()) }, hi)
    };
    let ymax = finite.iter().fold(0.0f64, |m, p| m.max(p.1)).max(1e-4) * 1.15;
    save_png(path, |buf| draw(report, &rows, &points, (lo, hi, ymax), aa, buf))
}

/// Draws a W x H chart into a buffer with `draw` and writes it to `path`.
fn save_png(path: &Path, draw: impl FnOnce(&mut [u8]) -> DrawResult) -> Result<()> {
    let mut buf = vec![255u8; (W * H * 3) as usize];
    draw(&mut buf).map_err(|e| anyhow!("drawing {}: {e}", path.display()))?;
    image::RgbImage::from_raw(W, H, buf)
        .context("plot buffer size")?
        .save(path)
        .with_context(|| format!("writing {}", path.display()))
}

/// One series: its line, its points and each point's label beside it, in
/// colour `k` of the palette, named in the legend.
fn draw_series<X, Y>(
    chart: &mut ChartContext<'_, BitMapBackend<'_>, Cartesian2d<X, Y>>,
    k: usize,
    label: &str,
    pts: &[(f64, f64, &str)],
) -> DrawResult
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let (r, g, b) = SERIES_COLORS[k % SERIES_COLORS.len()];
    let color = RGBColor(r, g, b).to_rgba();
    chart
        .draw_series(LineSeries::new(pts.iter().map(|p| (p.0, p.1)), color.stroke_width(2)))?
        .label(label)
        .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
    chart.draw_series(pts.iter().map(|p| Circle::new((p.0, p.1), 5, color.filled())))?;
    chart.draw_series(pts.iter().map(|p| {
        EmptyElement::at((p.0, p.1))
            + Text::new(p.2.to_string(), (8, -20), ("sans-serif", 15).into_font().color(&color))
    }))?;
    Ok(())
}

/// The legend, top right, and the finished image.
fn finish<'a, X, Y>(
    root: &DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>,
    chart: &mut ChartContext<'a, BitMapBackend<'a>, Cartesian2d<X, Y>>,
) -> DrawResult
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()?;
    root.present()?;
    Ok(())
}

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

fn draw(
    report: &Report,
    rows: &[&Row],
    points: &[(f64, f64)],
    (lo, hi, ymax): (f64, f64, f64),
    aa: bool,
    buf: &mut [u8],
) -> DrawResult {
    let root = BitMapBackend::with_buffer(buf, (W, H)).into_drawing_area();
    root.fill(&WHITE)?;
    let title = format!(
        "{}: {} ({}x{}, {})",
        if aa { "Anti-aliasing: 8-bit error vs GPU time" } else { "Image error vs GPU time" },
        report.scene.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
        report.width,
        report.height,
        report.device
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(80)
        .build_cartesian_2d((lo..hi).log_scale(), 0.0..ymax)?;
    chart
        .configure_mesh()
        .x_desc("median GPU frame time (ms, log scale)")
        .y_desc(if aa {
            "FLIP mean against the supersampled base, 8-bit images (lower is better)"
        } else {
            "FLIP mean against the reference (lower is better)"
        })
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|v| significant(*v, 3))
        .y_label_formatter(&|v| format!("{v:.4}"))
        .draw()?;
    let mut knobs: Vec<&'static str> = Vec::new();
    for r in rows {
        if !knobs.contains(&r.knob) {
            knobs.push(r.knob);
        }
    }
    for (k, knob) in knobs.iter().enumerate() {
        // (ms, error, label): the base setting, in every series, is
        // labelled once below.
        let series: Vec<(f64, f64, &str)> = rows
            .iter()
            .zip(points)
            .filter(|(r, p)| r.knob == *knob && p.0.is_finite() && p.0 > 0.0)
            .map(|(r, p)| (p.0, p.1, if r.measured == report.base { "" } else { r.value.as_str() }))
            .collect();
        draw_series(&mut chart, k, knob, &series)?;
    }
    if let Some(i) = rows.iter().position(|r| r.measured == report.base) {
        let p = points[i];
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(p)
                    + Rectangle::new([(-6, -6), (6, 6)], BLACK.stroke_width(2))
                    + Text::new("base", (8, 6), ("sans-serif", 15).into_font()),
            ))?
            .label("base settings (in every series)")
            .legend(|(x, y)| Rectangle::new([(x + 4, y - 6), (x + 16, y + 6)], BLACK.stroke_width(2)));
    }
    let front: Vec<(f64, f64)> = pareto_front(points).into_iter().map(|i| points[i]).collect();
    chart
        .draw_series(LineSeries::new(front.iter().copied(), BLACK.stroke_width(1)))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    chart.draw_series(front.iter().map(|p| Circle::new(*p, 9, BLACK.stroke_width(2))))?;
    finish(&root, &mut chart)
}

/// `v` with `digits` significant digits, trailing zeros dropped.
pub fn significant(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (digits - 1 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A labelled series of (x, y, point label) for [`curves`].
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64, String)>,
}

/// A plain line chart: one coloured series per entry (points labelled),
/// linear axes from 0, to `path` (PNG).
pub fn curves(path: &Path, title: &str, x_desc: &str, y_desc: &str, series: &[Series]) -> Result<()> {
    register_font()?;
    let all = || series.iter().flat_map(|s| &s.points).filter(|p| p.0.is_finite() && p.1.is_finite());
    let xmax = all().fold(0.0f64, |m, p| m.max(p.0)).max(1e-3) * 1.1;
    let ymax = all().fold(0.0f64, |m, p| m.max(p.1)).max(1e-4) * 1.15;
    save_png(path, |buf| draw_curves(buf, title, (x_desc, y_desc), (xmax, ymax), series))
}

fn draw_curves(
    buf: &mut [u8],
    title: &str,
    (x_desc, y_desc): (&str, &str),
    (xmax, ymax): (f64, f64),
    series: &[Series],
) -> DrawResult {
    let root = BitMapBackend::with_buffer(buf, (W, H)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..xmax, 0.0..ymax)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|v| significant(*v, 3))
        .y_label_formatter(&|v| format!("{v:.4}"))
        .draw()?;
    draw_lines(&mut chart, series, |x, y| x.is_finite() && y.is_finite())?;
    finish(&root, &mut chart)
}

/// Each series' points that `keep` accepts, in x order, as [`draw_series`] line `k`.
fn draw_lines<X, Y>(
    chart: &mut ChartContext<'_, BitMapBackend<'_>, Cartesian2d<X, Y>>,
    series: &[Series],
    keep: impl Fn(f64, f64) -> bool,
) -> DrawResult
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for (k, s) in series.iter().enumerate() {
        let mut pts: Vec<(f64, f64, &str)> =
            s.points.iter().filter(|p| keep(p.0, p.1)).map(|p| (p.0, p.1, p.2.as_str())).collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        draw_series(chart, k, &s.label, &pts)?;
    }
    Ok(())
}

/// [`curves`] on log-log axes (positive points only, each axis spanning them with a margin), for cost
/// against size: a straight line of slope 1 is linear growth.
pub fn log_curves(path: &Path, title: &str, x_desc: &str, y_desc: &str, series: &[Series]) -> Result<()> {
    register_font()?;
    let positive: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| &s.points)
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
        .map(|p| (p.0, p.1))
        .collect();
    let span = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
        if lo > hi {
            (1.0, 10.0)
        } else {
            // A margin around the points, at least a decade wide.
            (lo / 1.4, (hi * 1.4).max(lo * 10.0))
        }
    };
    let xs = span(&mut positive.iter().map(|p| p.0));
    let ys = span(&mut positive.iter().map(|p| p.1));
    save_png(path, |buf| draw_log_curves(buf, title, (x_desc, y_desc), (xs, ys), series))
}

fn draw_log_curves(
    buf: &mut [u8],
    title: &str,
    (x_desc, y_desc): (&str, &str),
    ((x0, x1), (y0, y1)): ((f64, f64), (f64, f64)),
    series: &[Series],
) -> DrawResult {
    let root = BitMapBackend::with_buffer(buf, (W, H)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|v| significant(*v, 2))
        .y_label_formatter(&|v| significant(*v, 2))
        .draw()?;
    draw_lines(&mut chart, series, |x, y| x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite())?;
    finish(&root, &mut chart)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let pts =
            [(10.0, 0.5), (20.0, 0.1), (15.0, 0.6), (30.0, 0.1), (5.0, 0.9), (40.0, 0.0), (f64::NAN, 0.0)];
        // (15, 0.6) is dominated by (10, 0.5); (30, 0.1) by (20, 0.1).
        assert_eq!(pareto_front(&pts), vec![4, 0, 1, 5]);
        assert_eq!(pareto_front(&[]), Vec::<usize>::new());
        // Equal time: only the lower error.
        assert_eq!(pareto_front(&[(1.0, 0.2), (1.0, 0.1)]), vec![1]);
        assert_eq!(significant(2.0000000004, 3), "2");
        assert_eq!(significant(0.012345, 3), "0.0123");
        assert_eq!(significant(1234.7, 3), "1235");
    }
}
