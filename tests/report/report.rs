//! `report` on a tiny case (two knob values at 32x18 on the bundled default
//! scene) checks its own numbers and files; `compare` and `bench --csv` end
//! to end through the binary.
use crate::common;
use common::split_csv;

use std::path::{Path, PathBuf};
use std::process::Command;

use hybrid_rt::app::{self, RenderJob};
use hybrid_rt::report::{self, knobs, metrics, write::CSV_HEADER, ReportOptions};

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    // The path-traced references these runs render are cached here, not in
    // the user's cache directory.
    let cache = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report-truth-cache");
    c.env("HYBRID_RT_VALIDATION", "1").env(report::truth::CACHE_DIR_ENV, cache);
    c
}

fn decoded_size(path: &Path) -> (u32, u32) {
    let img = image::open(path).unwrap_or_else(|e| panic!("{} does not decode: {e}", path.display()));
    (img.width(), img.height())
}

/// Pixels of a plot drawn in colour below its legend (the top 130 rows): the series' markers and
/// lines (axes, grid and text are grey). An empty plot has none.
fn plotted_pixels(path: &Path) -> usize {
    let img = image::open(path).unwrap().to_rgb8();
    img.enumerate_pixels()
        .filter(|(_, y, p)| *y >= 130 && p.0.iter().max().unwrap() - p.0.iter().min().unwrap() > 60)
        .count()
}

/// The report at 32x18 with max-depth 0 and 1 against the self reference
/// (`--ref self`): its ꟻLIP is 0 for an image against itself and positive
/// against a shifted copy, report.csv parses with the fixed header and one
/// row per knob value, report.md names the reference and the self-check,
/// the error map and the plot decode.
#[test]
fn tiny_report_checks_its_numbers_and_files() {
    let dir = tmp("tiny");
    let job = RenderJob::new(app::default_scene_path().unwrap(), 32, 18);
    let opts = ReportOptions {
        frames: 5,
        warmup: 1,
        knobs: knobs::parse_selection("max-depth=0:1").unwrap(),
        reference: report::ReferenceSettings::SELF,
        ..ReportOptions::new(job, &dir)
    };
    let ctx = common::validated_context();
    let rep = report::run(&ctx, &opts).expect("report runs");
    common::assert_validation_clean(&ctx);
    let files = report::write_all(&rep, &dir).expect("report writes");
    assert!(files.iter().all(|f| f.is_file()), "{files:?}");

    // The metric on a rendered image.
    let reference = &rep.reference().image;
    assert_eq!((reference.width, reference.height), (32, 18));
    let ldr = reference.tone_mapped(rep.reference_exposure);
    let same = metrics::flip(&ldr, &ldr).unwrap();
    assert_eq!(same.mean(), 0.0, "ꟻLIP of an image against itself");
    let mut shifted = ldr.clone();
    let row = 32 * 3;
    for y in 0..18 {
        shifted.rgb[y * row..(y + 1) * row].rotate_right(3 * 3);
    }
    let moved = metrics::flip(&ldr, &shifted).unwrap();
    assert!(moved.mean() > 0.0, "ꟻLIP against a copy shifted by 3 pixels: {}", moved.mean());

    // report.csv: the fixed header, one row per knob value, numbers.
    let csv = std::fs::read_to_string(dir.join("report.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    assert_eq!(header[..7].join(","), "knob,value,backend,ms_median,ms_p95,flip_mean,psnr");
    assert_eq!(header[..7].join(","), CSV_HEADER);
    let rows: Vec<Vec<String>> = lines.map(split_csv).collect();
    assert_eq!(rows.len(), 2, "{csv}");
    for (r, value) in rows.iter().zip(["0", "1"]) {
        assert_eq!(r.len(), header.len(), "{r:?}");
        assert_eq!((r[0].as_str(), r[1].as_str()), ("max-depth", value));
        assert!(["query", "pipeline", "compute"].contains(&r[2].as_str()), "backend {}", r[2]);
        let num = |i: usize| r[i].parse::<f64>().unwrap_or_else(|e| panic!("{}: {e} in {r:?}", header[i]));
        assert!(num(3) > 0.0 && num(4) >= num(3), "ms median/p95 {r:?}");
        assert!((0.0..=1.0).contains(&num(5)), "ꟻLIP {r:?}");
        assert!(num(6) > 0.0, "PSNR {r:?}");
        let camera_rays = header.iter().position(|h| *h == "rays_camera").unwrap();
        assert_eq!(num(camera_rays), 0.0, "hybrid traces no camera ray");
    }
    // Deeper recursion is closer to the reference (the scene has mirrors and glass).
    let flip = |i: usize| rows[i][5].parse::<f64>().unwrap();
    assert!(flip(1) < flip(0), "max-depth 1 should beat 0: {csv}");

    // report.md names the reference and prints the self-check.
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.contains("## Reference") && md.contains("pure-RT mode"), "{md}");
    assert!(md.contains("max depth 16, min weight 0.001"), "{md}");
    assert!(md.contains("Self-check: hybrid vs rt at equal settings"), "{md}");
    assert!(md.contains("tone-mapped: largest 8-bit channel difference"), "{md}");
    assert!(md.contains("| max-depth | 0 |") && md.contains("| max-depth | 1 |"), "{md}");

    // The worst setting's error map (reference size) and the plot decode.
    let worst = rep.worst_rows();
    assert_eq!(worst.len(), 1);
    let map = dir.join(report::write::error_map_name(worst[0]));
    assert_eq!(decoded_size(&map), (32, 18));
    let (w, h) = decoded_size(&dir.join("error_vs_time.png"));
    assert!(w > 0 && h > 0);
    let drawn = plotted_pixels(&dir.join("error_vs_time.png"));
    assert!(drawn > 100, "the plot draws no rows ({drawn} coloured pixels)");
    // The map is the worst row's error: not black, not uniform.
    let img = image::open(&map).unwrap().to_rgb8();
    let colours: std::collections::HashSet<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    let mean = img.as_raw().iter().map(|&v| v as f64).sum::<f64>() / img.as_raw().len() as f64;
    assert!(colours.len() > 8 && mean > 5.0, "error map: {} colours, mean {mean}", colours.len());
}

/// The aa knob's rows are measured against the supersampled base, not the
/// reference: their table is whole (the AA pass's times above it, no NaN
/// relMSE) and they are plotted apart from the other knobs' rows.
#[test]
fn aa_rows_have_their_own_table_and_plot() {
    let dir = tmp("aa_rows");
    let job = RenderJob::new(app::default_scene_path().unwrap(), 32, 18);
    let opts = ReportOptions {
        frames: 5,
        warmup: 1,
        knobs: knobs::parse_selection("max-depth=1,aa=none:edge").unwrap(),
        reference: report::ReferenceSettings::SELF,
        count_rays: false,
        ..ReportOptions::new(job, &dir)
    };
    let ctx = common::validated_context();
    let rep = report::run(&ctx, &opts).expect("report runs");
    common::assert_validation_clean(&ctx);
    let files = report::write_all(&rep, &dir).expect("report writes");
    assert!(report::plot::plotted_rows(&rep, false).iter().all(|r| r.knob != "aa"));
    let aa = report::plot::plotted_rows(&rep, true);
    assert!(aa.len() == 2 && aa.iter().all(|r| r.knob == "aa"), "{}", aa.len());
    let aa_plot = dir.join(report::AA_PLOT);
    assert!(files.contains(&aa_plot), "{files:?}");
    assert!(decoded_size(&aa_plot).0 > 0);
    assert!(plotted_pixels(&aa_plot) > 100, "the aa plot draws no rows");
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(!md.contains("NaN") && !md.contains("nan |"), "{md}");
    // Every table: its header, its separator, then only rows up to a blank line.
    let lines: Vec<&str> = md.lines().collect();
    for (i, l) in lines.iter().enumerate().filter(|(_, l)| l.starts_with("| knob |")) {
        assert!(lines[i + 1].starts_with("|---"), "no separator under {l}");
        for row in lines[i + 2..].iter().take_while(|r| !r.is_empty()) {
            assert!(row.starts_with('|'), "a line inside the table under {l}: {row}");
        }
    }
    assert!(md.contains("| aa | none |") && md.contains(report::AA_PLOT), "{md}");
}

fn write_png(path: &Path, w: u32, h: u32, shift: u32) {
    let img = image::RgbImage::from_fn(w, h, |x, y| {
        let v = (((x + shift) * 37 + y * 11) % 256) as u8;
        image::Rgb([v, v / 2, 255 - v])
    });
    img.save(path).unwrap();
}

/// `compare`: identical PNGs give ꟻLIP 0; different ones a positive ꟻLIP
/// and an error map; mismatched sizes and unreadable files fail with the
/// file named, a non-zero exit and no panic.
#[test]
fn compare_cli() {
    let d = tmp("compare");
    let (a, b, small) = (d.join("a.png"), d.join("b.png"), d.join("small.png"));
    write_png(&a, 40, 20, 0);
    write_png(&b, 40, 20, 2);
    write_png(&small, 20, 10, 0);
    let run =
        |x: &Path, y: &Path, extra: &[&str]| bin().arg("compare").arg(x).arg(y).args(extra).output().unwrap();

    let out = run(&a, &a, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("ꟻLIP mean 0.000000") && stdout.contains("PSNR inf dB"), "{stdout}");
    assert!(stdout.contains("largest 8-bit channel difference 0, 0.0% of pixels differ"), "{stdout}");

    let map = d.join("map.png");
    let out = run(&a, &b, &["--out", map.to_str().unwrap(), "--threshold", "0.05"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mean: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("ꟻLIP mean "))
        .unwrap_or_else(|| panic!("no ꟻLIP line: {stdout}"))
        .parse()
        .unwrap();
    assert!(mean > 0.0, "{stdout}");
    assert!(stdout.contains("pixels with ꟻLIP > 0.05:"), "{stdout}");
    assert_eq!(decoded_size(&map), (40, 20));

    let missing = d.join("missing.png");
    for (x, y, named) in [(&a, &small, &small), (&a, &missing, &missing)] {
        let out = run(x, y, &[]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "expected failure: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        let line = stderr.lines().find(|l| l.starts_with("error:")).unwrap_or_else(|| panic!("{stderr}"));
        assert!(line.contains(&named.display().to_string()), "does not name {}: {line}", named.display());
    }
}

/// `bench --csv` writes one row per variant and pass; the side-by-side
/// summary gives one ratio per variant, the median of the per-frame ratios
/// with its quartiles, and a word that agrees with it; the hybrid variant
/// (auto primary visibility) warms up until both visibility passes have run.
#[test]
fn bench_csv_and_ratio_words() {
    let d = tmp("bench");
    let csv = d.join("bench.csv");
    let out = bin()
        .args(["--no-rt", "bench", "--width", "16", "--height", "16", "--frames", "2", "--warmup", "1"])
        .args(["--compare-modes", "--csv"])
        .arg(&csv)
        .output()
        .unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stderr}");
    let both = hybrid_rt::render::visibility::FRAMES_TO_WARM_BOTH;
    assert!(
        stderr.contains(&format!("bench: warming up 1/2 ({both} frames): Hybrid"))
            && stderr.contains("bench: warming up 2/2 (1 frames): Rt")
            && stderr.contains("bench: measuring 2 variants interleaved"),
        "{stderr}"
    );
    let side: Vec<&str> = stdout.lines().skip_while(|l| !l.starts_with("side by side")).skip(1).collect();
    assert!(side[0].contains(" baseline ") && !side[0].contains('['), "{stdout}");
    // Two frame pairs: the per-frame ratios' median and quartiles, one ratio only.
    let ratio = side[1].split(" ms ").nth(1).unwrap_or_else(|| panic!("{stdout}")).trim_start();
    let nums: Vec<f64> = ratio
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .filter(|t| !t.is_empty())
        .take(3)
        .map(|t| t.parse().unwrap())
        .collect();
    assert!(nums.len() == 3 && nums[1] <= nums[0] && nums[0] <= nums[2] && nums[1] > 0.0, "{stdout}");
    assert!(ratio.starts_with(&format!("{:.3}x [", nums[0])), "{stdout}");
    let word = ["slower", "faster", "as fast"].into_iter().find(|w| ratio.contains(&format!("] {w} ")));
    let agrees = match word {
        Some("slower") => nums[0] > 1.0,
        Some("faster") => nums[0] < 1.0,
        Some(_) => (nums[0] - 1.0).abs() < 0.006,
        None => false,
    };
    assert!(agrees && !ratio.contains("paired"), "{stdout}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&header[..4], &["variant", "mode", "backend", "accel_update"]);
    let rows: Vec<&str> = lines.collect();
    let frames: Vec<&&str> = rows.iter().filter(|r| r.contains(",frame,")).collect();
    assert_eq!(frames.len(), 2, "{text}");
    assert!(frames[0].starts_with("1,hybrid,") && frames[1].starts_with("2,rt,"), "{text}");
    let median = header.iter().position(|h| *h == "ms_median").unwrap();
    for r in &rows {
        let fields = split_csv(r);
        assert_eq!(fields.len(), header.len(), "{r}");
        let ms: f64 = fields[median].parse().unwrap_or_else(|e| panic!("{e}: {r}"));
        assert!(ms >= 0.0, "{r}");
    }
}

/// `report` through the binary: bad --knobs and too few --frames are
/// refused with the problem named; a tiny run shows its progress on stderr,
/// prints the self-check and writes its files.
#[test]
fn report_cli() {
    let d = tmp("cli");
    let run = |args: &[&str]| {
        bin().args(["report", "--width", "16", "--height", "9", "--out"]).arg(&d).args(args).output().unwrap()
    };
    for (args, needle) in [
        (&["--knobs", "depth"][..], "max-depth"),
        (&["--knobs", "max-depth=99"], "0..=64"),
        (&["--frames", "3"], "at least 5"),
        (&["--ref-mode", "hybrid"], "--ref self"),
        (&["--ref-samples", "2"], "4 to"),
        (&["--ref", "self", "--attribution-samples", "8"], "leave out --ref self"),
    ] {
        let out = run(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && !stderr.contains("panicked"), "{args:?}: {stderr}");
        // Usage errors, all of them: exit code 2, as clap's own.
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        let line = stderr.lines().find(|l| l.starts_with("error:")).unwrap_or_else(|| panic!("{stderr}"));
        assert!(line.contains(needle), "{args:?}: '{needle}' not in {line}");
    }
    let out = run(&[
        "--knobs",
        "mode=hybrid",
        "--frames",
        "5",
        "--warmup",
        "1",
        "--no-ray-counts",
        "--attribution-samples",
        "8",
    ]);
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stderr}");
    // A line when each setting starts, and one with its times when it is
    // done: the path-traced reference, hybrid and rt (mode=hybrid is hybrid).
    assert!(stderr.contains("report [1/3] reference (16x9"), "{stderr}");
    assert!(stderr.lines().any(|l| l.starts_with("report [3/3]") && l.contains("ms median")), "{stderr}");
    assert!(stdout.contains("self-check, hybrid vs rt at equal settings: ꟻLIP"), "{stdout}");
    // The attribution's progress, and its file.
    assert!(stderr.contains("report: attribution [6/6] every term"), "{stderr}");
    assert!(stdout.contains("attribution.csv"), "{stdout}");
    let csv = std::fs::read_to_string(d.join("report.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "{csv}");
    assert!(csv.lines().nth(1).unwrap().starts_with("mode,hybrid,"), "{csv}");
}

/// The accel-update knob on a skinned model: each setting plays the
/// animation up to --time with its own renderer and update policy; the
/// update's passes are part of its time, and after the refits (or
/// rebuilds) the frame matches the base setting's, whose structures were
/// built at that pose. Without an animation the knob's own values are
/// skipped (noted in the report), and values given explicitly are an error.
#[test]
fn accel_update_knob_plays_the_animation() {
    let dir = tmp("accel_update");
    let mut job = RenderJob::new(common::shared_asset("gltf/Fox/glTF/Fox.gltf"), 32, 18);
    job.animation = Some("Run".into());
    job.time = 1.0;
    let opts = ReportOptions {
        frames: 5,
        warmup: 3,
        knobs: knobs::parse_selection("accel-update=refit:full").unwrap(),
        count_rays: false,
        attribution_samples: 0,
        ..ReportOptions::new(job, &dir)
    };
    let ctx = common::validated_context();
    let rep = report::run(&ctx, &opts).expect("report runs");
    common::assert_validation_clean(&ctx);
    let base = &rep.measured[rep.base];
    assert_eq!(rep.rows.len(), 2);
    for (row, value) in rep.rows.iter().zip(["refit", "full"]) {
        assert_eq!((row.knob, row.value.as_str()), ("accel-update", value));
        let m = &rep.measured[row.measured];
        assert_eq!(m.timing.frames, 5);
        assert!(m.timing.pass("skinning").is_some(), "{value}: no update pass timed: {:?}", m.timing.passes);
        assert!(base.timing.pass("skinning").is_none(), "a still frame runs no update");
        let d = metrics::compare_hdr(&base.image, &m.image, rep.reference_exposure).unwrap();
        eprintln!(
            "accel-update {value}: {:.3} ms, ꟻLIP vs the still frame {:.5}",
            m.timing.median, d.flip_mean
        );
        assert!(d.flip_mean < 1e-3, "{value}: the frame after 8 updates differs: ꟻLIP {}", d.flip_mean);
    }
    drop(ctx);

    // A scene that does not animate: an error with values, skipped without.
    let still = RenderJob::new(app::default_scene_path().unwrap(), 32, 18);
    let ctx = common::validated_context();
    let named = ReportOptions {
        knobs: knobs::parse_selection("accel-update=refit").unwrap(),
        ..ReportOptions::new(still.clone(), &dir)
    };
    let err = report::run(&ctx, &named).err().expect("accel-update=refit on a still scene is an error");
    assert!(format!("{err:#}").contains("not animated"), "{err:#}");
    let skipping = ReportOptions {
        frames: 5,
        warmup: 1,
        knobs: knobs::parse_selection("max-depth=0,accel-update").unwrap(),
        count_rays: false,
        attribution_samples: 0,
        ..ReportOptions::new(still, &dir)
    };
    let rep = report::run(&ctx, &skipping).expect("report runs");
    assert!(rep.rows.iter().all(|r| r.knob == "max-depth"), "accel-update rows on a still scene");
    assert_eq!(rep.skipped.iter().filter(|s| s.contains("not animated")).count(), 3, "{:?}", rep.skipped);
}

/// The budget knob: its shares are of the cost of tracing every visible
/// object, so share 1 renders the base settings' image and share 0 the
/// raster-only one.
#[test]
fn budget_knob_spans_raster_only_to_every_object_traced() {
    let dir = tmp("budget");
    let mut job = RenderJob::new(app::default_scene_path().unwrap(), 32, 18);
    // Under a budget the ambient is SH (AmbientMode::pick): so is the base it is compared with.
    job.settings.ambient = hybrid_rt::render::AmbientMode::Sh;
    let opts = ReportOptions {
        frames: 5,
        warmup: 1,
        knobs: knobs::parse_selection("budget=0:1,effects=none").unwrap(),
        count_rays: false,
        attribution_samples: 0,
        ..ReportOptions::new(job, &dir)
    };
    let ctx = common::validated_context();
    let rep = report::run(&ctx, &opts).expect("report runs");
    common::assert_validation_clean(&ctx);
    let row = |knob: &str, value: &str| {
        let r = rep.rows.iter().find(|r| r.knob == knob && r.value == value).expect("a row");
        &rep.measured[r.measured]
    };
    let same = |a: &report::measure::Measured, b: &report::measure::Measured| {
        metrics::compare_hdr(&a.image, &b.image, rep.reference_exposure).unwrap().flip_mean
    };
    let base = &rep.measured[rep.base];
    let (none, zero, one) = (row("effects", "none"), row("budget", "0"), row("budget", "1"));
    assert_eq!(same(zero, none), 0.0, "budget share 0 is the raster-only image");
    assert_eq!(same(one, base), 0.0, "budget share 1 is the base image");
    assert!(same(none, base) > 0.0, "the effects show in this view");
    assert!(one.timing.pass("heuristic").is_some(), "the budget's pass is timed: {:?}", one.timing.passes);
}

/// `report budget-paths`: every mode and share runs along the path; the
/// full-effects run is its own reference, share 0 renders the raster-only
/// frames in the modes without fallback (so the same error), and the
/// effects show.
#[test]
fn budget_paths_span_raster_only_to_full_effects_in_both_modes() {
    use hybrid_rt::report::budget_paths::{self, BudgetPathOptions, MODES};
    let opts = BudgetPathOptions {
        job: RenderJob::new(app::default_scene_path().unwrap(), 32, 18),
        out: tmp("budget_paths"),
        frames: 3,
        warmup: 1,
        shares: vec![0.0, 0.5],
    };
    let ctx = common::validated_context();
    let runs = budget_paths::run(&ctx, &opts).expect("the budget paths run");
    common::assert_validation_clean(&ctx);
    let find = |label: &str, share: Option<f64>| {
        runs.iter()
            .find(|r| r.label == label && r.share == share)
            .unwrap_or_else(|| panic!("no run {label} {share:?}"))
    };
    assert_eq!(runs.len(), 2 + MODES.len() * 2, "{runs:?}");
    assert_eq!(find("full effects", None).flip_mean, 0.0, "the reference is its own run");
    let raster = find("raster only", None);
    assert!(raster.flip_mean > 0.0, "the effects show along the path");
    for m in &MODES {
        let zero = find(m.label, Some(0.0));
        if m.fallback == hybrid_rt::render::budget::Fallback::None {
            assert_eq!(zero.flip_mean, raster.flip_mean, "{}: share 0 is raster only", m.label);
        }
        assert!(zero.heuristic_ms > 0.0, "{}: the heuristic pass is timed", m.label);
    }
    let table = budget_paths::table(&opts, &ctx.caps.name, &runs);
    assert!(table.contains("| effects | 0.50 |"), "{table}");
}

/// The default reference is the path-traced truth: report.md says so with
/// its noise, which is under half the smallest error; a second run reads it
/// from the cache (the same image, nothing rendered); a truncated cache
/// file is rendered again with a warning, never trusted.
#[test]
fn path_traced_reference_is_measured_and_cached() {
    let dir = tmp("truth");
    let cache = dir.join("cache");
    let job = RenderJob::new(app::default_scene_path().unwrap(), 32, 18);
    let opts = ReportOptions {
        frames: 5,
        warmup: 1,
        knobs: knobs::parse_selection("max-depth=0").unwrap(),
        count_rays: false,
        truth_cache: Some(cache.clone()),
        attribution_samples: 16,
        ..ReportOptions::new(job, &dir)
    };
    let ctx = common::validated_context();
    let first = report::run(&ctx, &opts).expect("report runs");
    let t = first.truth.clone().expect("a path-traced reference");
    assert!(!t.cached && t.samples >= 256, "{t:?}");
    // The default frame's error per term (each, then all) and per object.
    let a = first.attribution.as_ref().expect("an attribution against the truth");
    let names: Vec<&str> = a.rows.iter().map(|r| r.name.as_str()).collect();
    let expected: Vec<&str> =
        report::attribution::TERMS.iter().map(|t| t.name).chain(["every term"]).collect();
    assert_eq!(names, expected);
    assert_eq!(a.samples, 16);
    let base = first.measured[first.base].image.clone();
    let base_flip =
        metrics::compare_hdr(&first.reference().image, &base, first.reference_exposure).unwrap().flip_mean;
    assert!((a.base_flip - base_flip).abs() < 1e-9, "{} vs the base row's {base_flip}", a.base_flip);
    let every = a.rows.last().unwrap();
    // The truth's terms replace the traced ambient, which is already close at this size: the frame
    // with them is no further from the truth than the terms' own noise (their halves).
    assert!(
        every.flip_mean < a.base_flip + every.halves_flip,
        "every term supplied: {} vs {} (halves {})",
        every.flip_mean,
        a.base_flip,
        every.halves_flip
    );
    let ground = a.objects.iter().find(|o| o.name == "ground").expect("the ground in the object table");
    assert!(ground.pixels > 100 && ground.truth > 0.0 && ground.flip > 0.0);
    assert!(a.objects.iter().map(|o| o.pixels).sum::<usize>() <= 32 * 18);
    let smallest = first.rows.iter().map(|r| r.flip_mean).fold(f64::INFINITY, f64::min);
    assert!(t.noise() <= 0.5 * smallest || t.samples * 2 > opts.reference.max_samples, "{t:?} vs {smallest}");
    report::write_all(&first, &dir).expect("report writes");
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.contains("The path-traced ground truth") && md.contains("Its own noise"), "{md}");
    assert!(md.contains("| every term |") && md.contains("| ground |"), "{md}");
    let csv = std::fs::read_to_string(dir.join("attribution.csv")).unwrap();
    let width = common::split_csv(csv.lines().next().unwrap()).len();
    assert!(csv.lines().all(|l| common::split_csv(l).len() == width), "{csv}");
    assert!(csv.lines().any(|l| l.starts_with("object,ground,")), "{csv}");

    let again = report::run(&ctx, &opts).expect("report runs again");
    let t2 = again.truth.clone().expect("a path-traced reference");
    assert!(t2.cached && t2.samples == t.samples, "{t2:?}");
    assert_eq!(again.reference().image.rgb, first.reference().image.rgb, "the cached image");

    let files: Vec<_> = std::fs::read_dir(&cache).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(files.len(), 1, "{files:?}");
    let bytes = std::fs::read(&files[0]).unwrap();
    std::fs::write(&files[0], &bytes[..bytes.len() / 2]).unwrap();
    let third = report::run(&ctx, &opts).expect("report runs with a truncated cache file");
    assert!(!third.truth.as_ref().unwrap().cached, "a truncated file was trusted");
    assert_eq!(third.reference().image.rgb, first.reference().image.rgb, "rendered again, the same seeds");
    common::assert_validation_clean(&ctx);
}

/// `bench --budget-ms` prints the budget's own overhead: the `heuristic`
/// pass's median as a share of the frame's (issue 41 item 11).
#[test]
fn bench_prints_the_budget_heuristics_share_of_the_frame() {
    let out = bin()
        .args([
            "bench",
            "--width",
            "32",
            "--height",
            "18",
            "--frames",
            "3",
            "--warmup",
            "1",
            "--budget-ms",
            "5",
        ])
        .output()
        .unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stderr}");
    let median = |name: &str| -> f64 {
        let line = stdout
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("{stdout}"));
        line.split_whitespace().nth(2).unwrap().parse().unwrap()
    };
    let (pass, frame) = (median("heuristic"), median("frame"));
    let line =
        stdout.lines().find(|l| l.starts_with("budget heuristic: ")).unwrap_or_else(|| panic!("{stdout}"));
    let share: f64 = line
        .strip_prefix(&format!("budget heuristic: {pass:.3} ms, "))
        .and_then(|r| r.strip_suffix(" % of the frame"))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    // The table's medians are rounded to 1 µs: the share agrees within its own rounding.
    assert!((share - 100.0 * pass / frame).abs() <= 0.06 + 100.0 * 0.0005 / frame, "{line} vs {stdout}");
}
