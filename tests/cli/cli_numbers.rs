//! Numbers in and out of the command line: every numeric flag is range
//! checked by the parser (usage error, exit code 2, the flag named), negative
//! numbers reach that check instead of being taken for flags, options that
//! would have no effect are refused, and a frame with non-finite pixels is
//! written with them marked (failing only with `--strict`).
use crate::common;

use std::path::PathBuf;
use std::process::{Command, Output};

use hybrid_rt::app;
use hybrid_rt::render::FrameOutput;

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    c.env("HYBRID_RT_VALIDATION", "1");
    c
}

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_numbers").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `command` with `args`, small unless the case sets the size itself (so a
/// value that is wrongly accepted renders quickly and the test fails fast).
fn run(command: &str, args: &[&str], out: &std::path::Path) -> Output {
    let mut c = bin();
    c.arg(command);
    for (flag, v) in [("--width", "16"), ("--height", "16")] {
        if !args.contains(&flag) {
            c.args([flag, v]);
        }
    }
    if command == "render" {
        c.arg("--out").arg(out);
    } else {
        c.args(["--warmup", "0"]);
        if !args.contains(&"--frames") {
            c.args(["--frames", "1"]);
        }
    }
    c.args(args).output().unwrap()
}

/// A usage error: exit code 2, no panic, the message names `flag`.
fn assert_usage_error(out: &Output, flag: &str, what: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{what}: expected exit code 2; stderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{what}: panicked:\n{stderr}");
    let error_line = stderr
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("{what}: no error line:\n{stderr}"));
    assert!(error_line.contains(flag), "{what}: error does not name {flag}: {error_line}");
}

#[test]
fn out_of_range_numbers_are_usage_errors() {
    let d = tmp("range");
    let png = d.join("x.png");
    let cases: &[(&str, &[&str], &str)] = &[
        ("render", &["--exposure", "nan"], "--exposure"),
        ("render", &["--exposure", "inf"], "--exposure"),
        ("render", &["--exposure", "0"], "--exposure"),
        ("render", &["--exposure", "-1"], "--exposure"),
        ("render", &["--look-from", "0,1,5", "--look-at", "0,0,0", "--fov", "0"], "--fov"),
        ("render", &["--look-from", "0,1,5", "--look-at", "0,0,0", "--fov", "180"], "--fov"),
        ("render", &["--look-from", "0,1,5", "--look-at", "0,0,0", "--fov", "-30"], "--fov"),
        ("render", &["--max-depth", "100000"], "--max-depth"),
        ("render", &["--max-depth", "-1"], "--max-depth"),
        ("render", &["--min-weight", "nan"], "--min-weight"),
        ("render", &["--min-weight", "-0.5"], "--min-weight"),
        ("render", &["--min-weight", "2"], "--min-weight"),
        ("render", &["--budget", "-1"], "--budget"),
        ("render", &["--budget", "nan"], "--budget"),
        ("render", &["--budget", "1000", "--stickiness", "-1"], "--stickiness"),
        ("render", &["--budget", "1000", "--stickiness", "inf"], "--stickiness"),
        ("render", &["--animation", "0", "--time", "nan"], "--time"),
        ("render", &["--animation", "0", "--time", "inf"], "--time"),
        ("render", &["--width", "0"], "--width"),
        ("render", &["--width", "-5"], "--width"),
        ("render", &["--height", "0"], "--height"),
        ("render", &["--height", "-3"], "--height"),
        ("render", &["--look-from", "nan,1,5", "--look-at", "0,0,0"], "--look-from"),
        ("bench", &["--frames", "0"], "--frames"),
        ("bench", &["--animation", "0", "--fps", "0"], "--fps"),
        ("bench", &["--animation", "0", "--fps", "nan"], "--fps"),
    ];
    for (command, args, flag) in cases {
        let what = format!("{command} {}", args.join(" "));
        assert_usage_error(&run(command, args, &png), flag, &what);
        assert!(!png.exists(), "{what}: wrote an image");
    }
}

/// An option that would change nothing is refused, not silently ignored.
#[test]
fn options_without_effect_are_usage_errors() {
    let png = tmp("noeffect").join("x.png");
    assert_usage_error(&run("render", &["--fov", "30"], &png), "--fov", "--fov without --look-from");
    assert_usage_error(&run("render", &["--time", "1"], &png), "--time", "--time without --animation");
    assert_usage_error(&run("bench", &["--fps", "10"], &png), "--fps", "--fps without --animation");
    let sticky = run("render", &["--stickiness", "2"], &png);
    assert_usage_error(&sticky, "--stickiness", "--stickiness without --budget");
    let fallback = run("render", &["--fallback", "none"], &png);
    assert_usage_error(&fallback, "--fallback", "--fallback without --budget");
    let fps = bin()
        .args(["report", "--animation", "0", "--fps", "10", "--knobs", "max-depth", "--out"])
        .arg(tmp("noeffect").join("report"))
        .output()
        .unwrap();
    assert_usage_error(&fps, "--fps", "--fps on report without the accel-update knob");
}

/// Negative values parse where they are valid, and mean what they say: a
/// camera position with a negative coordinate (the view from the mirrored
/// position differs) and an animation time before the start (the clip
/// loops: -2.5 s is the pose at its duration - 2.5 s, not at +2.5 s).
#[test]
fn negative_numbers_parse() {
    let d = tmp("negative");
    let scene = common::shared_asset("gltf/BoxAnimated/glTF-Binary/BoxAnimated.glb");
    let duration = hybrid_rt::scene::Scene::load(&scene).unwrap().animations[0].duration;
    let render = |from: &str, time: &str| -> Vec<u8> {
        let png = d.join(format!("x_{from}_{time}.png"));
        let out = bin()
            .args(["render", "--width", "16", "--height", "16", "--look-from", from, "--look-at", "0,0,0"])
            .args(["--fov", "40", "--animation", "0", "--time", time, "--scene"])
            .arg(&scene)
            .arg("--out")
            .arg(&png)
            .output()
            .unwrap();
        assert!(out.status.success(), "{from} {time}: {}", String::from_utf8_lossy(&out.stderr));
        image::open(&png).unwrap().to_rgb8().into_raw()
    };
    let largest = |a: &[u8], b: &[u8]| a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
    // (The clip's poses at t and -t agree for most t: 2.5 s is one where they do not.)
    let image = render("-2,1,-3", "-2.5");
    let looped = render("-2,1,-3", &format!("{}", duration - 2.5));
    assert!(largest(&image, &looped) <= 2, "-2.5 s is not the pose at {} s", duration - 2.5);
    assert!(largest(&image, &render("-2,1,-3", "2.5")) > 20, "-2.5 s rendered the pose at +2.5 s");
    assert!(largest(&image, &render("2,1,-3", "-2.5")) > 20, "-2 rendered the view from +2");
}

/// A negative coordinate on the command line puts the camera where it says:
/// the view from (-2, 2.5, 4) of a scene is the left-right mirror of the
/// view from (2, 2.5, 4) of the scene's mirror image (a red cube at x = -1
/// instead of +1 on a grey floor, a sun in the x = 0 plane, a black sky).
#[test]
fn negative_coordinates_mirror_the_view() {
    use common::toml::*;
    let d = tmp("mirror");
    let (w, h) = (48u32, 32u32);
    let render = |cube_x: f32, from: &str| -> image::RgbImage {
        let scene = d.join(format!("cube_at_{cube_x}.toml"));
        let text = scene_toml([
            black_sky(),
            camera([0.0, 2.5, 4.0], [0.0, 0.5, 0.0]),
            directional([0.0, -1.0, -0.6], 3.0),
            lambert("grey", [0.5, 0.5, 0.5]),
            lambert("red", [0.8, 0.1, 0.1]),
            plane("floor", 8.0).material("grey"),
            cube("marker", 1.5).at([cube_x, 0.75, 0.0]).material("red"),
        ]);
        std::fs::write(&scene, text).unwrap();
        let png = d.join(format!("cube_at_{cube_x}_from_{from}.png"));
        let out = bin()
            // A fixed exposure: the scene authors none, and auto exposure would amplify the traced
            // ambient's (unmirrored) noise pattern.
            .args(["render", "--width", &w.to_string(), "--height", &h.to_string(), "--exposure", "1"])
            .args(["--look-from", from])
            .args(["--look-at", "0,0.5,0", "--scene"])
            .arg(&scene)
            .arg("--out")
            .arg(&png)
            .output()
            .unwrap();
        assert!(out.status.success(), "{from}: {}", String::from_utf8_lossy(&out.stderr));
        image::open(&png).unwrap().to_rgb8()
    };
    let mirrored = |img: &image::RgbImage| image::imageops::flip_horizontal(img);
    // Pixels whose channels differ by more than 8/255 (edges may: the
    // rasterizer's tie rule and the triangles' diagonals are not mirrored).
    let differing = |a: &image::RgbImage, b: &image::RgbImage| {
        a.pixels()
            .zip(b.pixels())
            .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 8))
            .count()
    };
    let right = render(1.0, "2,2.5,4");
    let left = render(-1.0, "-2,2.5,4");
    let n = (w * h) as usize;
    let red = left.pixels().filter(|p| p[0] as u32 > 2 * p[1].max(p[2]) as u32 && p[0] > 40).count();
    assert!(red > n / 20, "the cube is not in view: {red} red pixels of {n}");
    let off = differing(&mirrored(&right), &left);
    assert!(off <= n / 100, "{off} of {n} pixels differ from the mirrored view");
    // The check can fail: neither view is its own mirror image.
    assert!(differing(&mirrored(&left), &left) > n / 20, "the view is left-right symmetric");
}

/// The accepted ranges are in the help text.
#[test]
fn help_documents_the_ranges() {
    let out = bin().args(["render", "--help"]).output().unwrap();
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for range in ["finite, > 0", "(0, 180)", "0..=64", "[0, 1]", "1..=16384", "--strict"] {
        assert!(help.contains(range), "render --help does not mention '{range}':\n{help}");
    }
}

/// A 3x2 frame, every pixel mid grey, with NaN at (2, 0) and +Inf at (1, 1).
fn frame_with_non_finite_pixels() -> FrameOutput {
    let (width, height) = (3u32, 2u32);
    let mut hdr = vec![0.5f32; (width * height * 4) as usize];
    let mut ldr = vec![128u8; (width * height * 4) as usize];
    hdr[2 * 4 + 1] = f32::NAN;
    hdr[(width + 1) as usize * 4] = f32::INFINITY;
    // What a tone mapper may make of them: nothing that stands out.
    ldr[2 * 4..2 * 4 + 4].copy_from_slice(&[0, 0, 0, 255]);
    FrameOutput::from_images(width, height, ldr, hdr)
}

/// Non-finite pixels are counted, written marked (magenta PNG, zero HDR)
/// and do not fail the write; with `strict` the images are still written
/// and the call fails naming the count and the first pixel.
#[test]
fn non_finite_pixels_are_marked_and_fail_only_when_strict() {
    let frame = frame_with_non_finite_pixels();
    assert_eq!(app::non_finite_pixels(&frame), (2, Some((2, 0))));
    for strict in [false, true] {
        let d = tmp(&format!("nonfinite-{strict}"));
        let (png, hdr) = (d.join("x.png"), d.join("x.hdr"));
        let result = app::write_outputs(&frame, &png, Some(&hdr), strict);
        match (strict, &result) {
            (false, Ok(n)) => assert_eq!(*n, 2),
            (true, Err(e)) => {
                let msg = format!("{e:#}");
                assert!(
                    msg.contains("--strict") && msg.contains("2 pixel") && msg.contains("(2, 0)"),
                    "{msg}"
                );
            }
            _ => panic!(
                "strict {strict}: unexpected result {:?}",
                result.as_ref().map_err(|e| format!("{e:#}"))
            ),
        }
        let img = image::open(&png).unwrap().into_rgb8();
        assert_eq!(img.get_pixel(2, 0).0, [255, 0, 255], "NaN pixel not magenta");
        assert_eq!(img.get_pixel(1, 1).0, [255, 0, 255], "Inf pixel not magenta");
        assert_eq!(img.get_pixel(0, 0).0, [128, 128, 128], "finite pixel changed");
        let radiance = image::open(&hdr).unwrap().into_rgb32f();
        assert_eq!(radiance.get_pixel(2, 0).0, [0.0; 3], "NaN pixel not zero in the HDR");
        assert_eq!(radiance.get_pixel(1, 1).0, [0.0; 3], "Inf pixel not zero in the HDR");
        assert!((radiance.get_pixel(0, 0).0[0] - 0.5).abs() < 0.01, "finite pixel changed in the HDR");
    }
    // A clean frame passes strict.
    let mut clean = frame_with_non_finite_pixels();
    clean.hdr.iter_mut().for_each(|v| *v = 0.25);
    let d = tmp("nonfinite-clean");
    assert_eq!(app::write_outputs(&clean, &d.join("x.png"), None, true).unwrap(), 0);
}

/// `--strict` is accepted by `render` and passes on a finite frame.
#[test]
fn strict_render_of_a_finite_frame_succeeds() {
    let d = tmp("strict");
    let out = run("render", &["--strict"], &d.join("x.png"));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(d.join("x.png").exists());
}
