//! `report stability` on a subset of its cases at 64x36 on the bundled
//! default scene, every available backend, validation on: the thresholds
//! of those cases hold, report.csv parses with the exact header, report.md
//! states the thresholds; and the command line refuses bad input.
use crate::common;
use common::split_csv;

use std::path::PathBuf;
use std::process::Command;

use hybrid_rt::app::{self, RenderJob};
use hybrid_rt::report::stability::{self, write::CSV_HEADER, StabilityOptions};

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("stability").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The cases asserted here (their canonicals come along).
const SUBSET: [&str; 5] = ["translate-1e3", "scale-1e-3", "ior-1.0", "env-texel-1e5", "zero-area-triangles"];

/// Every failed expectation, so one run shows them all.
#[derive(Default)]
struct Problems(Vec<String>);

impl Problems {
    fn check(&mut self, ok: bool, what: impl FnOnce() -> String) {
        if !ok {
            self.0.push(what());
        }
    }
}

#[test]
fn stability_subset_meets_its_thresholds() {
    let dir = tmp("subset");
    let job = RenderJob::new(app::default_scene_path().unwrap(), 64, 36);
    let opts = StabilityOptions {
        frames: 3,
        warmup: 1,
        cases: SUBSET.iter().map(|s| s.to_string()).collect(),
        ..StabilityOptions::new(job, &dir)
    };
    let ctx = common::validated_context();
    let rep = stability::run(&ctx, &opts).expect("the stability report runs");
    common::assert_validation_clean(&ctx);
    let files = stability::write::write_all(&rep, &dir).expect("the stability report writes");
    assert!(files.iter().all(|f| f.is_file()), "{files:?}");
    let mut p = Problems::default();

    // Every backend ran or was skipped with a note; lavapipe has all three.
    let names: Vec<&str> = rep.cases.iter().map(|c| c.0).collect();
    assert_eq!(
        names,
        [
            "origin",
            "translate-1e3",
            "scale-1e-3",
            "origin-rough",
            "ior-1.0",
            "env-map",
            "env-texel-1e5",
            "obj-panel",
            "zero-area-triangles"
        ]
    );
    let backends = rep.rows.iter().filter(|r| r.case == "origin").count();
    p.check(backends + rep.skipped.len() == 3, || {
        format!("{backends} backends run, skipped {:?}", rep.skipped)
    });
    p.check(backends == 3, || format!("lavapipe offers query, pipeline and compute: {:?}", rep.skipped));
    assert_eq!(rep.rows.len(), names.len() * backends);

    let row = |case: &str, backend: &str| {
        rep.rows.iter().find(|r| r.case == case && r.backend == backend).expect("a row per case and backend")
    };
    for r in &rep.rows {
        p.check(r.error.is_none(), || format!("{} on {}: {:?}", r.case, r.backend, r.error));
        p.check(r.finite_pct == 100.0, || format!("{} on {}: finite {} %", r.case, r.backend, r.finite_pct));
        p.check(r.ms_median > 0.0, || format!("{} on {}: {} ms", r.case, r.backend, r.ms_median));
        let at = |c: &str| SUBSET.contains(&c);
        // The thresholds report.md states, checked here independently of
        // the report's own verdict, and that verdict too.
        let what =
            format!("{} on {}: PSNR {:.2} dB, max 8-bit diff {}", r.case, r.backend, r.psnr, r.max_ldr_diff);
        match r.case {
            "translate-1e3" | "scale-1e-3" => p.check(r.psnr >= 80.0, || format!("{what}, want >= 80 dB")),
            "ior-1.0" | "zero-area-triangles" => {
                p.check(r.max_ldr_diff <= 2, || format!("{what}, want <= 2"))
            }
            "env-texel-1e5" => {
                let base = row("env-map", &r.backend);
                p.check(r.psnr >= 40.0, || format!("{what}, want >= 40 dB"));
                p.check(r.white_pct <= base.white_pct + 0.5, || {
                    format!("{what}: white {} % against {} % without the texel", r.white_pct, base.white_pct)
                });
            }
            _ => {}
        }
        if at(r.case) {
            p.check(r.pass(), || format!("{} on {}: the report fails it: {:?}", r.case, r.backend, r.failed));
        }
    }
    // The compared-with cases are the canonical ones.
    for (case, against) in
        [("translate-1e3", "origin"), ("ior-1.0", "origin-rough"), ("env-texel-1e5", "env-map")]
    {
        p.check(row(case, "compute").against == against, || {
            format!("{case} compared with {}", row(case, "compute").against)
        });
    }

    // report.csv: the exact leading header, one parsable row per case and backend.
    let csv = std::fs::read_to_string(dir.join("report.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    p.check(header[..7].join(",") == "case,backend,finite_pct,flip_mean,psnr,ms_median,pass", || {
        format!("header {header:?}")
    });
    assert_eq!(CSV_HEADER, "case,backend,finite_pct,flip_mean,psnr,ms_median,pass");
    let rows: Vec<Vec<String>> = lines.map(split_csv).collect();
    p.check(rows.len() == rep.rows.len(), || {
        format!("{} CSV rows for {} results", rows.len(), rep.rows.len())
    });
    for r in &rows {
        p.check(r.len() == header.len(), || {
            format!("{} fields for {} columns: {r:?}", r.len(), header.len())
        });
        let num = |i: usize| r[i].parse::<f64>().unwrap_or(f64::NAN);
        p.check(names.contains(&r[0].as_str()), || format!("case {}", r[0]));
        p.check(["query", "pipeline", "compute"].contains(&r[1].as_str()), || format!("backend {}", r[1]));
        p.check(num(2) == 100.0, || format!("finite_pct {r:?}"));
        p.check((0.0..=1.0).contains(&num(3)), || format!("flip_mean {r:?}"));
        p.check(num(4) > 0.0, || format!("psnr {r:?}"));
        p.check(num(5) > 0.0, || format!("ms_median {r:?}"));
        p.check(r[6] == "true" || r[6] == "false", || format!("pass {r:?}"));
        p.check(!SUBSET.contains(&r[0].as_str()) || r[6] == "true", || format!("failing row {r:?}"));
    }

    // report.md states the thresholds and has a row per result.
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for needle in [
        "## Thresholds",
        "finite 100 %",
        "| translate-1e3 | origin | PSNR >= 80 dB |",
        "| ior-1.0 | origin-rough | max 8-bit difference <= 2 |",
        "| env-texel-1e5 | env-map | PSNR >= 40 dB, white % <= white % of env-map + 0.5 |",
        "| zero-area-triangles | obj-panel | max 8-bit difference <= 2 |",
        "## Limits that remain",
    ] {
        p.check(md.contains(needle), || format!("report.md lacks '{needle}'"));
    }
    for r in &rep.rows {
        let verdict = if r.pass() { "| pass |" } else { "| **FAIL** |" };
        let start = format!("| {} | {} | 100.00 |", r.case, r.backend);
        p.check(md.lines().any(|l| l.starts_with(&start) && l.ends_with(verdict)), || {
            format!("report.md: no row '{start} ... {verdict}'")
        });
    }
    for r in &rep.rows {
        let png = dir.join("images").join(format!("{}_{}.png", r.case, r.backend));
        p.check(image::open(&png).is_ok_and(|i| (i.width(), i.height()) == (64, 36)), || {
            format!("{} does not decode at 64x36", png.display())
        });
    }
    assert!(p.0.is_empty(), "{} problem(s):\n{}", p.0.len(), p.0.join("\n"));
}

/// The command line: progress per case on stderr, the files written; bad
/// case names, options of other reports, --cases without --stability (the
/// earlier spelling) and too few frames refused.
#[test]
fn stability_cli() {
    let d = tmp("cli");
    // `report stability ARGS` (sub = true) or `report ARGS`.
    let run_as = |sub: bool, args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
            .env("HYBRID_RT_VALIDATION", "1")
            .arg("report")
            .args(if sub { &["stability"][..] } else { &[] })
            .args(["--width", "64", "--height", "36", "--out"])
            .arg(&d)
            .args(args)
            .output()
            .unwrap()
    };
    let run = |args: &[&str]| run_as(true, args);
    let mut p = Problems::default();
    for (sub, args, needle) in [
        (true, &["--cases", "nope"][..], "translate-1e3"),
        (true, &["--frames", "2"], "at least 3"),
        (true, &["--knobs", "mode"], "unexpected argument '--knobs'"),
        (true, &["--ref-samples", "64"], "unexpected argument '--ref-samples'"),
        (false, &["--cases", "origin"], "--stability"),
        (false, &["--stability", "--knobs", "mode"], "--knobs"),
    ] {
        let out = run_as(sub, args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        p.check(!out.status.success() && !stderr.contains("panicked"), || format!("{args:?} ran: {stderr}"));
        p.check(stderr.contains(needle), || format!("{args:?}: '{needle}' not in {stderr}"));
    }
    let out = run(&["--cases", "scale-1e3", "--frames", "3", "--warmup", "1"]);
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    p.check(out.status.success(), || format!("the run failed: {stderr}"));
    p.check(
        stderr.contains("stability [1/2] origin") && stderr.contains("stability [2/2] scale-1e3"),
        || format!("no progress lines: {stderr}"),
    );
    p.check(stdout.contains("of 6 case/backend rows pass"), || format!("no summary: {stdout}"));
    let csv = std::fs::read_to_string(d.join("report.csv")).unwrap_or_default();
    p.check(csv.lines().count() == 7, || format!("not 6 rows: {csv}"));
    p.check(csv.starts_with(CSV_HEADER), || format!("header: {csv}"));
    assert!(p.0.is_empty(), "{} problem(s):\n{}", p.0.len(), p.0.join("\n"));
}
