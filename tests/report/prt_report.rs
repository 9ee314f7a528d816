//! `report prt` end to end (src/report/prt.rs) on the plane under a
//! sphere (tests/common/scenes.rs) under a constant environment: the report
//! renders the ray-traced reference and the selected transfers and gives
//! one row per variant with its precompute, composite and frame times; PRT
//! shadowed is closer to the reference than unshadowed (the sphere's
//! underside sees the floor, which only the shadowed transfer and the
//! reference know about); the files it writes hold those rows.
use crate::common;

use std::path::PathBuf;

use hybrid_rt::app::{EnvOverrides, RenderJob};
use hybrid_rt::render::ReferenceSettings;
use hybrid_rt::report::prt::{self, PrtReportOptions};
use hybrid_rt::scene::EnvLayout;

#[test]
fn prt_report_rows_and_shadowed_beats_unshadowed() {
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    std::env::set_var(hybrid_rt::prt::CACHE_DIR_ENV, tmp.join("prt-report-cache"));
    let scene = tmp.join("scenes").join("prt_report_plane_sphere.toml");
    std::fs::create_dir_all(scene.parent().unwrap()).unwrap();
    std::fs::write(&scene, common::scenes::plane_under_sphere()).unwrap();
    let map = common::write_hdr("prt_report_constant", 32, 16, |_, _| [1.0; 3]);
    let job = RenderJob {
        env: EnvOverrides { map: Some((map, EnvLayout::Equirect)), ..Default::default() },
        settings: hybrid_rt::render::RenderSettings {
            prt: hybrid_rt::render::PrtOptions { samples: 16, ..Default::default() },
            ..Default::default()
        },
        ..RenderJob::new(&scene, 48, 27)
    };
    let opts = PrtReportOptions {
        frames: 5,
        warmup: 1,
        knobs: prt::parse_selection("transfer=prt-unshadowed:prt-shadowed,bands=3,sh-samples=exact").unwrap(),
        reference: ReferenceSettings { samples: 64, bounces: 1 },
        ..PrtReportOptions::new(job, tmp.join("prt-report-out"))
    };
    let ctx = common::validated_context();
    let report = prt::run(&ctx, &opts).unwrap();
    let got: Vec<_> = report
        .rows
        .iter()
        .map(|r| (r.setting.transfer.as_str(), r.setting.bands, r.setting.sh_samples.as_str()))
        .collect();
    assert_eq!(got, [("prt-unshadowed", 3, "exact"), ("prt-shadowed", 3, "exact")]);
    for r in &report.rows {
        let m = &report.measured[r.measured];
        let p = r.precompute.expect("a PRT row has a precompute");
        assert!(p.seconds.is_finite() || !p.computed, "{:?}", r.setting);
        assert!(m.pass_ms("composite") > 0.0 && m.timing.median >= m.pass_ms("composite"), "{:?}", m.timing);
        assert!(r.flip_mean.is_finite() && r.psnr.is_finite());
    }
    let (unshadowed, shadowed) = (report.rows[0].flip_mean, report.rows[1].flip_mean);
    println!(
        "ꟻLIP against the reference: prt-unshadowed {unshadowed:.5}, prt-shadowed {shadowed:.5}; reference \
         at {} vs 64 samples {:.5}",
        report.convergence.0, report.convergence.1
    );
    assert!(shadowed < unshadowed, "shadowed {shadowed} is not below unshadowed {unshadowed}");
    // The reference's own noise is below what shadowing changes.
    assert!(
        report.convergence.1 < unshadowed - shadowed,
        "reference not converged: {}",
        report.convergence.1
    );
    let files = hybrid_rt::report::prt_write::write_all(&report, &opts.out).unwrap();
    assert!(files.iter().any(|f| f.ends_with("prt_error_vs_time.png")));
    // The plot draws the rows where their numbers say: the shadowed row's marker (blue, the second
    // series colour) below the unshadowed one's (red), outside the legend (the top 120 rows).
    let plot = image::open(opts.out.join("prt_error_vs_time.png")).unwrap().to_rgb8();
    let centre_y = |is: fn(&image::Rgb<u8>) -> bool| {
        let ys: Vec<u32> =
            plot.enumerate_pixels().filter(|(_, y, p)| *y > 120 && is(p)).map(|(_, y, _)| y).collect();
        assert!(ys.len() > 20, "{} marker pixels", ys.len());
        ys.iter().sum::<u32>() as f64 / ys.len() as f64
    };
    let red = centre_y(|p| p[0] > 200 && p[1] < 80 && p[2] < 80);
    let blue = centre_y(|p| p[2] > 150 && p[0] < 100);
    assert!(blue > red, "the shadowed marker (y {blue}) is not drawn below the unshadowed one (y {red})");
    let csv = std::fs::read_to_string(opts.out.join("prt.csv")).unwrap();
    let lines: Vec<_> = csv.lines().collect();
    assert_eq!(lines.len(), 3, "{csv}");
    assert!(
        lines[1].contains(",prt-unshadowed,3,exact,16,") && lines[2].contains(",prt-shadowed,3,exact,16,"),
        "{csv}"
    );
    drop(ctx); // validation errors, teardown included, fail here
}

/// Bad `report prt` input (or its earlier spelling `report --prt`): a
/// usage error (exit 2, checked before anything renders) naming the knob and
/// value or the flag; no panic, nothing written.
#[test]
fn prt_report_bad_input_is_named() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("prt-report-bad");
    let _ = std::fs::remove_dir_all(&out);
    for (args, code, says) in [
        (&["--prt", "--knobs", "bands=9"][..], 2, "bands 9"),
        (&["--prt", "--knobs", "sh-samples=many"], 2, "sh-samples 'many'"),
        (&["--prt", "--knobs", "transfer=prt-interreflected-0"], 2, "transfer 'prt-interreflected-0'"),
        (&["prt", "--knobs", "max-depth"], 2, "unknown knob 'max-depth' for report prt"),
        (&["prt", "--sweep", "--knobs", "bands=9"], 2, "bands 9"),
        (&["prt", "--ref-samples", "64"], 2, "unexpected argument '--ref-samples'"),
        (&["--prt-sweep"], 2, "--prt"),
        (&["--prt", "--stability"], 2, "--stability"),
    ] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
            .arg("report")
            .args(args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: error does not say {says}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}
