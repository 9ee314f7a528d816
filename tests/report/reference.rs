//! The ray-traced reference for diffuse environment light
//! (`--reference-samples`, render/reference.rs, glsl/passes/reference.glsl).
//!
//! - A constant environment L over an unoccluded plane: every cosine sample
//!   misses and brings L, so the reference equals `--ambient constant`
//!   (E/pi = L) per sample, on every backend, to float rounding (1e-4
//!   relative). Without the flag no pass and no target exist.
//! - A plane under a sphere (radius r, centre at height d above the point
//!   P): the sphere hides the cap of projected solid angle pi r^2 d / D^3
//!   from a plane point at distance D from the centre (pi (r/d)^2 at P), so
//!   the reference over the constant ambient is 1 - r^2 d / D^3 per pixel.
//!   Averaged over the plane pixels within 0.3 of P at N = 1024 the
//!   Bernoulli noise is sd <= 0.5 / sqrt(1024 M) (M pixels): the bound is
//!   5 sd plus 0.005 for the sphere's 64x32 tessellation.
//! - Convergence: RMS error over the plane against the N = 1024 image falls
//!   with N (16, 64, 256): by more than 0.65 per 4x (1/sqrt(4) = 0.5 for
//!   independent samples; these share the first frames' seeds with the
//!   N = 1024 image, sd ~ sqrt(1/N - 1/1024), still below 0.5 a step).
//! - A moved camera starts the accumulation over: its first frame equals a
//!   fresh renderer's first frame bit for bit.
//! - All three backends trace the same rays (same seeds): with 2 bounces
//!   the images agree within 1e-3 mean absolute difference relative to the
//!   mean, and 99% of pixels within 1% (a ray grazing the sphere's edges
//!   may hit on one traversal and miss on another; on lavapipe they are
//!   bit-identical).
//! - Bad flag values are usage errors naming the flag.
use crate::common;

use ash::vk::Extent2D;
use common::toml::*;
use common::Bench;
use glam::Vec3;
use hybrid_rt::app::EnvOverrides;
use hybrid_rt::render::shading::Backend;
use hybrid_rt::render::{AmbientMode, FrameOutput, ReferenceSettings, RenderSettings, Renderer};
use hybrid_rt::scene::{Camera, EnvLayout, Scene};

const L: [f32; 3] = [0.6, 0.45, 0.3];

/// A ground plane, a sphere of radius 0.5 centred 1.0 above the origin
/// (`sphere` false: no sphere), a camera looking down at the origin, no
/// light: the frame is emission-free ambient alone.
fn plane_toml(sphere: bool) -> String {
    let ball = sphere.then(|| common::toml::sphere("ball", 0.5).at([0.0, 1.0, 0.0]).material("white"));
    let blocks = [
        camera([0.0, 1.6, 2.4], [0.0; 3]).yfov(40),
        camera([1.8, 1.2, 1.8], [0.0, 0.3, 0.0]).yfov(50),
        no_light(),
        lambert("white", [0.8; 3]),
        plane("ground", [40.0, 40.0]).material("white"),
    ];
    scene_toml(blocks.into_iter().chain(ball))
}

/// The scene lit by a constant map of radiance `L`.
fn scene(name: &str, sphere: bool) -> Scene {
    let map = common::write_hdr("reference_constant", 32, 16, |_, _| L);
    let mut scene = common::scene_from_toml(name, &plane_toml(sphere));
    EnvOverrides { map: Some((map, EnvLayout::Equirect)), ..Default::default() }.apply(&mut scene).unwrap();
    scene
}

fn reference(samples: u32, bounces: u32, backend: Backend) -> RenderSettings {
    RenderSettings { reference: Some(ReferenceSettings { samples, bounces }), backend, ..Default::default() }
}

/// The converged reference of `settings` (all its frames, from scratch).
fn converged(b: &mut Bench, scene: &Scene, camera: &Camera, settings: &RenderSettings) -> FrameOutput {
    let out =
        hybrid_rt::render::reference::render_converged(&mut b.renderer, &b.ctx, scene, camera, settings)
            .unwrap();
    assert!(out.all_finite(), "NaN or Inf reached the frame");
    out
}

#[test]
fn constant_environment_over_an_open_plane_equals_the_constant_ambient() {
    let scene = scene("reference_open", false);
    let cam = scene.cameras[0].clone();
    let mut b = Bench::new(&scene, 64, 36);
    let constant =
        b.frame(&scene, &cam, &RenderSettings { ambient: AmbientMode::Constant, ..Default::default() });
    // Leave-out: without the flag no pass and no accumulation target.
    assert!(!b.renderer.pass_names().contains(&"reference"), "{:?}", b.renderer.pass_names());
    assert!(b.renderer.targets().describe().iter().all(|(n, _)| !n.contains("reference")));
    for backend in common::BACKENDS {
        for bounces in [1, 3] {
            let r = converged(&mut b, &scene, &cam, &reference(8, bounces, backend));
            assert!(b.renderer.pass_names().contains(&"reference"), "{:?}", b.renderer.pass_names());
            let mut worst = 0.0f32;
            for (a, c) in r.hdr.iter().zip(&constant.hdr) {
                worst = worst.max((a - c).abs() / c.abs().max(1e-3));
            }
            println!("{backend:?}, {bounces} bounce(s): largest relative difference {worst:e}");
            assert!(worst <= 1e-4, "{backend:?}, {bounces} bounce(s): reference vs constant ambient {worst}");
        }
    }
    b.finish();
}

/// Mean over `pixels` of (reference / constant ambient) in red.
fn mean_ratio(r: &FrameOutput, constant: &FrameOutput, pixels: &[(usize, Vec3)]) -> f64 {
    pixels.iter().map(|(i, _)| (r.hdr[i * 4] / constant.hdr[i * 4]) as f64).sum::<f64>() / pixels.len() as f64
}

fn rms_error(a: &FrameOutput, b: &FrameOutput, constant: &FrameOutput, pixels: &[(usize, Vec3)]) -> f64 {
    let s: f64 = pixels
        .iter()
        .map(|(i, _)| ((a.hdr[i * 4] - b.hdr[i * 4]) / constant.hdr[i * 4]) as f64)
        .map(|e| e * e)
        .sum();
    (s / pixels.len() as f64).sqrt()
}

/// The plane under the sphere against 1 - r^2 d / D^3; the error against
/// the N = 1024 image falls with N; a moved camera starts over.
#[test]
fn plane_under_a_sphere_matches_the_analytic_occlusion_and_converges() {
    let (w, h) = (128, 72);
    let scene = scene("reference_sphere", true);
    let cam = scene.cameras[0].clone();
    let mut b = Bench::new(&scene, w, h);
    let constant =
        b.frame(&scene, &cam, &RenderSettings { ambient: AmbientMode::Constant, ..Default::default() });
    let pixels = common::ground_pixels(&cam, w, h, 0.3);
    assert!(pixels.len() >= 20, "only {} ground pixels near the origin", pixels.len());
    let (r, d) = (0.5f64, 1.0f64);
    let expected = pixels
        .iter()
        .map(|(_, p)| {
            let dd = (p.length_squared() as f64 + d * d).sqrt();
            1.0 - r * r * d / dd.powi(3)
        })
        .sum::<f64>()
        / pixels.len() as f64;
    // One accumulation of 1024 samples, read at 16, 64 and 256 (the same
    // images as separate renders: the seeds are the frame indices).
    let settings = reference(1024, 1, Backend::Auto);
    let mut snapshots = Vec::new();
    let frames = settings.reference.unwrap().frames();
    b.renderer.reset_reference();
    let mut last = None;
    for f in 1..=frames {
        let out = b.frame(&scene, &cam, &settings);
        if [4, 16, 64].contains(&f) {
            snapshots.push(out);
            continue;
        }
        last = Some(out);
    }
    let full = last.unwrap();
    let ratio = mean_ratio(&full, &constant, &pixels);
    let sd = 0.5 / (1024.0 * pixels.len() as f64).sqrt();
    let bound = 5.0 * sd + 0.005;
    println!(
        "{} pixels: reference / constant {ratio:.4}, analytic {expected:.4} (1 - (r/d)^2 = {:.4} at P), bound {bound:.4}",
        pixels.len(),
        1.0 - (r / d).powi(2)
    );
    assert!((ratio - expected).abs() <= bound, "occlusion: {ratio} vs analytic {expected} (bound {bound})");
    let errors: Vec<f64> = snapshots.iter().map(|s| rms_error(s, &full, &constant, &pixels)).collect();
    println!("RMS error against N = 1024 at N = 16, 64, 256: {errors:?}");
    for k in 1..errors.len() {
        assert!(errors[k] < 0.65 * errors[k - 1], "error does not fall like 1/sqrt(N): {errors:?}");
    }
    // Two bounces: the sphere's underside, lit by the environment it sees
    // (at most L) times its albedo 0.8, fills in part of what it hides:
    // brighter than visibility alone, at most 1 - 0.2 (1 - analytic).
    let two = converged(&mut b, &scene, &cam, &reference(256, 2, Backend::Auto));
    let ratio2 = mean_ratio(&two, &constant, &pixels);
    let most = 1.0 - 0.2 * (1.0 - expected);
    println!("2 bounces: reference / constant {ratio2:.4} (visibility only {ratio:.4}, at most {most:.4})");
    assert!(
        ratio2 > ratio + 0.01 && ratio2 <= most + bound,
        "2 bounces: {ratio2} vs {ratio}, at most {most}"
    );
    // A moved camera starts over: its first frame is a fresh renderer's.
    let other = scene.cameras[1].clone();
    let moved = b.frame(&scene, &other, &settings);
    b.finish();
    let mut fresh = Bench::new(&scene, w, h);
    let first = fresh.frame(&scene, &other, &settings);
    fresh.finish();
    assert!(moved.hdr == first.hdr, "the moved camera's frame mixes in the old view's accumulation");
}

/// Same seeds, same rays: the three backends agree (2 bounces: the sphere
/// and the plane light each other).
#[test]
fn every_backend_gives_the_same_image() {
    let (w, h) = (96, 54);
    let scene = scene("reference_backends", true);
    let cam = scene.cameras[1].clone();
    let mut b = Bench::new(&scene, w, h);
    let images: Vec<FrameOutput> =
        common::BACKENDS.iter().map(|&be| converged(&mut b, &scene, &cam, &reference(16, 2, be))).collect();
    b.finish();
    let base = &images[0];
    let mean = base.hdr.iter().map(|v| *v as f64).sum::<f64>() / base.hdr.len() as f64;
    for (be, img) in common::BACKENDS.iter().zip(&images).skip(1) {
        let diff: Vec<f64> = img.hdr.iter().zip(&base.hdr).map(|(a, b)| (a - b).abs() as f64).collect();
        let mad = diff.iter().sum::<f64>() / diff.len() as f64;
        let off = img
            .hdr
            .chunks_exact(4)
            .zip(base.hdr.chunks_exact(4))
            .filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| (x - y).abs() > 0.01 * y.abs().max(1e-3)))
            .count();
        println!(
            "{be:?} vs {:?}: mean |difference| {:.3e} of the mean, {off} of {} pixels differ by > 1%",
            common::BACKENDS[0],
            mad / mean,
            w * h
        );
        assert!(mad <= 1e-3 * mean, "{be:?}: mean difference {mad} vs mean {mean}");
        assert!(off as f64 <= 0.01 * (w * h) as f64, "{be:?}: {off} pixels differ by more than 1%");
    }
}

/// Bad values are usage errors naming the flag; a good one renders.
#[test]
fn reference_flags() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reference_cli");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("x.png");
    let _ = std::fs::remove_file(&out); // an earlier run's
    let cases: [(&[&str], &str); 6] = [
        (&["--reference-samples", "0"], "--reference-samples"),
        (&["--reference-samples", "many"], "--reference-samples"),
        (&["--reference-samples", "-4"], "--reference-samples"),
        (&["--reference-samples", "4", "--reference-bounces", "0"], "--reference-bounces"),
        (&["--reference-bounces", "2"], "--reference-samples"),
        (&["--reference-samples", "4", "--debug-view", "normal"], "--reference-samples"),
    ];
    for (args, flag) in cases {
        let o = common::tiny_render_cmd().args(args).arg("--out").arg(&out).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?}: error does not name {flag}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote an image");
    }
    // report renders one frame per variant: refused, not silently 4 samples.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
        .args(["report", "--reference-samples", "64", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "report: {err}");
    assert!(err.contains("--reference-samples"), "report: {err}");
    let o = common::tiny_render_cmd()
        .args(["--reference-samples", "6", "--reference-bounces", "2", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("reference: 8 samples per pixel in 2 frames"), "{err}");
    assert!(out.exists());
}

/// The accumulation is read and written every frame, across submissions:
/// synchronization validation stays clean on every backend, hybrid and
/// pure RT, and the pass sits between `direct` and `composite`.
#[test]
fn accumulation_is_clean_under_synchronization_validation() {
    let ctx = common::sync_validated_context();
    let scene = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    for backend in common::BACKENDS {
        for mode in [hybrid_rt::render::shading::Mode::Hybrid, hybrid_rt::render::shading::Mode::Rt] {
            let settings = RenderSettings { mode, ..reference(12, 2, backend) };
            let mut r = Renderer::new(&ctx, &scene, Extent2D { width: 32, height: 18 }).unwrap();
            let out = hybrid_rt::render::reference::render_converged(
                &mut r,
                &ctx,
                &scene,
                &scene.cameras[0],
                &settings,
            )
            .unwrap();
            assert!(out.all_finite(), "{backend:?} {mode:?}: NaN or Inf");
            let names = r.pass_names();
            let at =
                |n: &str| names.iter().position(|p| *p == n).unwrap_or_else(|| panic!("{n} in {names:?}"));
            assert!(at("direct") < at("reference") && at("reference") < at("composite"), "{names:?}");
            assert_eq!(r.reference_frames(), 3, "{backend:?} {mode:?}");
            r.destroy(&ctx);
        }
    }
    common::assert_validation_clean(&ctx);
}
