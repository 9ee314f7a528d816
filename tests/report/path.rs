//! The path-traced ground truth (`--mode path`, glsl/path/path.glsl).
//!
//! - White furnace: under a constant sky L, objects whose BSDF conserves
//!   energy exactly (white Lambert at IOR 1, a white perfect mirror, clear
//!   glass, and a rough white metal through the GGX lobe's multiple-scattering
//!   compensation, glsl/common/split_sum.glsl) are invisible: every pixel is
//!   L in expectation, interreflections between them included; the hybrid
//!   frame too (its split-sum environment specular on the rough metal).
//!   Held per object (the pixels well inside its outline) to 0.6% at 1024
//!   paths per pixel (the noise of a mean under 0.1%; glass that reflects
//!   10% too little reads -1%), every pixel to 10% (the rough metal's rim,
//!   the noisiest, measured 6%; 15% at 256 paths).
//! - Closed furnace: inside a closed diffuse shell of albedo a emitting E,
//!   radiance is E / (1 - a) everywhere (the sum of all bounces); its error
//!   falls as 1 / sqrt(N): RMS over the pixels at N = 4, 16, 64 shrinks by
//!   0.5 per 4x (held to [0.42, 0.58]; the RMS of 1,536 pixels is known to
//!   ~2%), and the mean at N = 64 is within 1% of E / (1 - a).
//! - Direct light is exact in the hybrid frame on an open plane under
//!   punctual lights and a black sky (one bounce, nothing to reflect):
//!   there the path tracer's next-event estimation must agree with it on a
//!   glossy (GGX over Lambert) plane under point, spot and directional
//!   lights: means to 0.2% (measured 1e-4), every pixel to 6% against the
//!   hybrid frame box-filtered over 8x8 samples (the paths' jitter filters
//!   the pixel with 16 random ones).
//! - The environment's importance sampling, with MIS against the BSDF
//!   samples, agrees with the ambient reference pass (cosine sampling
//!   only, an independent estimator) on a diffuse sphere that fills the
//!   frame under a rotated HDR map with a sun.
//! - Glass blocks the sun's shadow rays (it bends light): the shadow of a
//!   glass sphere under a sun and a black sky is black in path mode.
//! - Volume attenuation (KHR_materials_volume), exact: through a clear
//!   IOR-1 cube of side 1 whose medium turns white light (0.5, 0.8, 1) per
//!   unit, a constant sky L arrives as L c^(len) with len the ray's path
//!   inside (1 / |d.z| along the axis): per pixel to 0.2% in path mode
//!   and in the hybrid frame's refraction chain.
//! - All three backends trace the same paths (same seeds): their images
//!   agree to 1e-3 mean absolute difference over the mean, and under 1% of
//!   values differ by over 1% (lavapipe: 3e-7, none).
use crate::common;

use common::toml::*;

use ash::vk::Extent2D;
use hybrid_rt::app::EnvOverrides;
use hybrid_rt::render::shading::{AaMode, Backend, Mode};
use hybrid_rt::render::supersample::{render_supersampled, SampleFilter, Supersample};
use hybrid_rt::render::{
    AmbientMode, FrameOutput, PathSettings, ReferenceSettings, RenderSettings, Renderer,
};
use hybrid_rt::scene::{EnvLayout, Scene};

const W: u32 = 48;
const H: u32 = 32;

fn path(samples: u32, backend: Backend) -> RenderSettings {
    RenderSettings {
        mode: Mode::Path,
        path: PathSettings { samples, ..Default::default() },
        backend,
        ..Default::default()
    }
}

/// Renders `settings` to convergence (all its frames) from the first camera.
fn converged(scene: &Scene, w: u32, h: u32, settings: &[RenderSettings]) -> Vec<FrameOutput> {
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, scene, Extent2D { width: w, height: h }).unwrap();
    let mut out = Vec::new();
    for s in settings {
        let f = hybrid_rt::render::reference::render_converged(&mut r, &ctx, scene, &scene.cameras[0], s)
            .unwrap();
        assert!(f.all_finite(), "NaN or Inf reached the frame");
        out.push(f);
    }
    r.destroy(&ctx);
    drop(ctx); // validation errors, teardown included, fail here
    out
}

/// Mean of channel `c` over the pixels (x, y) with `keep(x, y)`.
fn mean(f: &FrameOutput, c: usize, keep: impl Fn(u32, u32) -> bool) -> f64 {
    let (mut s, mut n) = (0.0, 0);
    for y in 0..f.height {
        for x in 0..f.width {
            if keep(x, y) {
                s += f.radiance(x, y)[c] as f64;
                n += 1;
            }
        }
    }
    s / n as f64
}

#[test]
fn white_furnace_objects_vanish_in_a_constant_sky() {
    let l = 0.5f32;
    let toml = scene_toml([
        environment([l, l, l]),
        no_light(),
        camera([0.0, 0.0, 6.0], [0.0; 3]).yfov(30),
        lambert("lambert", [1.0; 3]).ior(1.0),
        mirror("mirror", [1.0; 3]),
        glass("glass", 1.5),
        material("rough metal").base([1.0; 3]).metallic(1.0).roughness(0.8),
        sphere("lambert", 0.7).at([-0.8, 0.8, 0.0]).material("lambert"),
        sphere("mirror", 0.7).at([0.8, 0.8, 0.0]).material("mirror"),
        sphere("glass", 0.7).at([-0.8, -0.8, 0.0]).material("glass"),
        sphere("rough metal", 0.7).at([0.8, -0.8, 0.0]).material("rough metal"),
    ]);
    let scene = common::scene_from_toml("path_white_furnace", &toml);
    let f = &converged(&scene, W, H, &[path(1024, Backend::Compute)])[0];
    // The split sum's energy alone: the traced ambient's specular occlusion would shade a sphere its
    // neighbours hide part of the sky from.
    let sh = RenderSettings { ambient: AmbientMode::Sh, ..Default::default() };
    let hybrid = common::render_scene(&scene, W, H, &sh);
    let cam = &scene.cameras[0];
    let spheres =
        [("lambert", -0.8, 0.8), ("mirror", 0.8, 0.8), ("glass", -0.8, -0.8), ("rough metal", 0.8, -0.8)];
    for (name, x, y) in spheres {
        // The pixels whose centre ray passes well inside the sphere's outline.
        let centre = glam::Vec3::new(x, y, 0.0);
        let inside = |x: u32, y: u32| {
            let (o, d) = common::pixel_ray(cam, W, H, x, y);
            (centre - o - d * (centre - o).dot(d)).length() < 0.6
        };
        let n = (0..W * H).filter(|i| inside(i % W, i / W)).count();
        let m = mean(f, 1, inside);
        println!("{name}: mean over {n} pixels {m:.5} (sky {l})");
        assert!(n > 50, "{name}: {n} pixels");
        assert!((m / l as f64 - 1.0).abs() < 0.006, "{name}: {m} against the sky's {l}");
        // The hybrid's rough metal: the split-sum table's albedo times its compensation is 1 at
        // f0 = 1, to the table's half-float steps.
        if name == "rough metal" {
            let m = mean(&hybrid, 1, inside);
            println!("hybrid {name}: mean {m:.5}");
            assert!((m / l as f64 - 1.0).abs() < 0.006, "hybrid {name}: {m} against the sky's {l}");
        }
    }
    let (at, worst) = f
        .hdr
        .chunks(4)
        .map(|p| (p[1] / l - 1.0).abs())
        .enumerate()
        .fold((0, 0.0f32), |a, (i, d)| if d > a.1 { (i, d) } else { a });
    println!("largest per-pixel deviation {worst:.4} at ({}, {})", at as u32 % W, at as u32 / W);
    assert!(worst < 0.1, "pixel ({}, {}) is off by {worst}", at as u32 % W, at as u32 / W);
}

/// A closed shell (the camera inside a sphere) of albedo `A` emitting `E`.
fn shell() -> Scene {
    let toml = scene_toml([
        black_sky(),
        no_light(),
        camera([0.3, 0.2, 0.5], [-1.0, -0.3, -2.0]).yfov(70),
        lambert("shell", [0.5; 3]).ior(1.0).emissive([1.0; 3]),
        sphere("shell", 3.0).material("shell"),
    ]);
    common::scene_from_toml("path_closed_furnace", &toml)
}

#[test]
fn closed_furnace_converges_to_the_sum_of_all_bounces_as_one_over_root_n() {
    let expected = 1.0 / (1.0 - 0.5);
    let scene = shell();
    let runs = [4, 16, 64].map(|n| path(n, Backend::Compute));
    let frames = converged(&scene, W, H, &runs);
    let rms: Vec<f64> = frames
        .iter()
        .map(|f| {
            let s: f64 = (0..W * H).map(|i| (f.radiance(i % W, i / W)[1] as f64 - expected).powi(2)).sum();
            (s / (W * H) as f64).sqrt()
        })
        .collect();
    let m = mean(&frames[2], 1, |_, _| true);
    println!("RMS error at N = 4, 16, 64: {rms:?}; mean at 64: {m:.5} (expected {expected})");
    assert!((m / expected - 1.0).abs() < 0.01, "mean {m}, expected {expected}");
    for w in rms.windows(2) {
        let ratio = w[1] / w[0];
        assert!((0.42..=0.58).contains(&ratio), "RMS error fell by {ratio} for 4x the samples: {rms:?}");
    }
}

/// The linear value whose 8-bit sRGB encoding is exactly `byte`: the
/// G-buffer stores albedo so, and any other value is rounded there (by up
/// to 0.5% at 0.6), which the path tracer, reading the material, is not.
fn srgb_byte(byte: u8) -> f32 {
    let c = byte as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A plane of a material (`finish` of one whose base colour is stored
/// exactly) lit by a sun, a point light and a spot under a black sky, seen
/// from above: one bounce, nothing else.
fn lit_plane(finish: fn(Block) -> Block) -> Scene {
    let base = [204, 180, 160].map(srgb_byte);
    let toml = scene_toml([
        black_sky(),
        camera([0.0, 3.0, 2.5], [0.0, 0.0, -0.3]).yfov(45),
        directional([-0.3, -1.0, -0.5], 1.5),
        point([0.8, 1.2, 0.2], 3.0).color([1.0, 0.6, 0.3]),
        light("spot")
            .set("position", [-1.0, 2.0, 0.5])
            .set("target", [-0.5, 0.0, -0.5])
            .cones(10, 35)
            .color([0.3, 0.5, 1.0])
            .intensity(20.0),
        finish(material("glossy").base(base)),
        plane("ground", [40.0, 40.0]).material("glossy"),
    ]);
    common::scene_from_toml("path_lit_plane", &toml)
}

#[test]
fn next_event_estimation_matches_the_exact_direct_light_of_the_hybrid_frame() {
    // A glossy dielectric (GGX over Lambert), and a rough metal where the
    // GGX lobe is all there is (its shadowing term matters most).
    direct_light_agrees(&lit_plane(|m| m.roughness(0.5)), "glossy dielectric");
    direct_light_agrees(&lit_plane(|m| m.metallic(1.0).roughness(0.8)), "rough metal");
}

fn direct_light_agrees(scene: &Scene, what: &str) {
    let p = &converged(scene, W, H, &[path(16, Backend::Compute)])[0];
    // The hybrid frame box-filtered over 8x8 samples a pixel, as the paths'
    // jittered camera rays filter it.
    let ctx = common::validated_context();
    let hybrid = RenderSettings { aa: AaMode::None, backend: Backend::Compute, ..Default::default() };
    let ss = Supersample { factor: 8, filter: SampleFilter::Box };
    let extent = Extent2D { width: W, height: H };
    let h = &render_supersampled(&ctx, scene, &scene.cameras[0], extent, &hybrid, &ss).unwrap();
    drop(ctx);
    let mut worst = 0.0f64;
    let mut over = 0;
    for y in 0..H {
        for x in 0..W {
            let (a, b) = (h.radiance(x, y), p.radiance(x, y));
            let e = (0..3).map(|c| ((b[c] - a[c]).abs() / a[c].max(1e-3)) as f64).fold(0.0, f64::max);
            worst = worst.max(e);
            over += (e > 0.02) as u32;
        }
    }
    let share = over as f64 / (W * H) as f64;
    println!("{what}: largest relative difference {worst:.4}, {:.2}% of pixels over 2%", share * 100.0);
    for c in 0..3 {
        let (mh, mp) = (mean(h, c, |_, _| true), mean(p, c, |_, _| true));
        println!("channel {c}: hybrid {mh:.5}, path {mp:.5}");
        assert!((mp / mh - 1.0).abs() < 0.002, "{what}, channel {c}: path {mp} against the exact {mh}");
    }
    // Per pixel, 16 jittered paths against 64 regular samples of the
    // pixel's area: where a highlight or the spot's edge crosses a pixel
    // they differ by a few %.
    assert!(worst < 0.06, "a pixel differs by {worst}");
    assert!(share <= 0.05, "{:.2}% of pixels differ by more than 2% (largest {worst})", share * 100.0);
}

#[test]
fn environment_importance_sampling_agrees_with_the_cosine_sampled_reference() {
    // A white Lambert sphere filling the frame under a rotated HDR map: the
    // ambient reference (cosine samples, visibility) is exact there too.
    let toml = scene_toml([
        no_light(),
        camera([0.0, 0.0, 2.2], [0.0; 3]).yfov(30),
        lambert("white", [0.8; 3]).ior(1.0),
        sphere("ball", 1.0).slices(128, 64).material("white"),
    ]);
    let mut scene = common::scene_from_toml("path_env_sampling", &toml);
    let map = common::repo_path("assets/potsdamer_platz_512.hdr");
    EnvOverrides { map: Some((map, EnvLayout::Equirect)), rotation_deg: Some(57.0), intensity: Some(1.0) }
        .apply(&mut scene)
        .unwrap();
    let reference = RenderSettings {
        aa: AaMode::None,
        backend: Backend::Compute,
        reference: Some(ReferenceSettings { samples: 1024, bounces: 1 }),
        ..Default::default()
    };
    let frames = converged(&scene, W, H, &[reference, path(256, Backend::Compute)]);
    let (r, p) = (&frames[0], &frames[1]);
    let mut ratios: Vec<f64> = (0..W * H)
        .map(|i| (p.radiance(i % W, i / W)[1] / r.radiance(i % W, i / W)[1].max(1e-6)) as f64)
        .collect();
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    let (p5, p95) = (ratios[ratios.len() / 20], ratios[ratios.len() * 19 / 20]);
    println!("path / reference per pixel: median {median:.4}, 5% {p5:.4}, 95% {p95:.4}");
    for c in 0..3 {
        let (mr, mp) = (mean(r, c, |_, _| true), mean(p, c, |_, _| true));
        println!("channel {c}: reference {mr:.5}, path {mp:.5}");
        assert!((mp / mr - 1.0).abs() < 0.005, "channel {c}: path {mp}, reference {mr}");
    }
    // Per pixel mostly the reference's own noise (1,024 cosine samples).
    assert!((median - 1.0).abs() < 0.01, "median ratio {median}");
    assert!(p5 > 0.85 && p95 < 1.15, "ratio spread {p5} .. {p95}");
}

/// A floor, a clear glass sphere above it and a sun straight down, black sky.
fn glass_over_floor(extra: Option<Block>) -> Scene {
    let toml = scene_toml(
        [
            black_sky(),
            camera([0.0, 3.5, 3.5], [0.0; 3]).yfov(40),
            directional([0.0, -1.0, 0.0], 2.0),
            lambert("floor", [0.7; 3]).ior(1.0),
            glass("glass", 1.5),
            mirror("metal", [0.9, 0.7, 0.4]).roughness(0.4),
            plane("floor", [40.0, 40.0]).material("floor"),
            sphere("glass", 0.6).at([0.0, 1.0, 0.0]).material("glass"),
        ]
        .into_iter()
        .chain(extra),
    );
    common::scene_from_toml("path_glass_floor", &toml)
}

/// The pixel nearest to where the camera sees world point p.
fn pixel_of(scene: &Scene, p: glam::Vec3) -> (u32, u32) {
    let cam = &scene.cameras[0];
    let mut best = (0, 0, f32::MAX);
    for y in 0..H {
        for x in 0..W {
            let (o, d) = common::pixel_ray(cam, W, H, x, y);
            let miss = (p - o - d * (p - o).dot(d)).length();
            if miss < best.2 {
                best = (x, y, miss);
            }
        }
    }
    (best.0, best.1)
}

#[test]
fn glass_casts_a_dark_shadow_in_path_mode() {
    let scene = glass_over_floor(None);
    let hybrid = RenderSettings { aa: AaMode::None, backend: Backend::Compute, ..Default::default() };
    let frames = converged(&scene, W, H, &[hybrid, path(16, Backend::Compute)]);
    // Inside the shadow (a disc of radius 0.6 under the sphere), on its
    // side towards the camera, which sees it past the sphere.
    let (sx, sy) = pixel_of(&scene, glam::Vec3::new(0.0, 0.0, 0.45));
    let (lx, ly) = pixel_of(&scene, glam::Vec3::new(1.8, 0.0, 0.8));
    for (f, name) in frames.iter().zip(["hybrid", "path"]) {
        let (s, l) = (f.radiance(sx, sy)[1], f.radiance(lx, ly)[1]);
        println!("{name}: shadow {s:.4}, lit floor {l:.4}");
    }
    let shade = |f: &FrameOutput| f.radiance(sx, sy)[1] / f.radiance(lx, ly)[1];
    assert!(shade(&frames[0]) > 0.5, "the hybrid frame's transmittance shadow: {}", shade(&frames[0]));
    assert!(
        shade(&frames[1]) < 0.2,
        "path mode: light through glass along a straight ray: {}",
        shade(&frames[1])
    );
}

#[test]
fn backends_trace_the_same_paths() {
    let metal = sphere("metal", 0.5).at([1.3, 0.5, 0.3]).material("metal");
    let mut scene = glass_over_floor(Some(metal));
    let map = common::repo_path("assets/potsdamer_platz_512.hdr");
    EnvOverrides { map: Some((map, EnvLayout::Equirect)), ..Default::default() }.apply(&mut scene).unwrap();
    let runs: Vec<RenderSettings> = common::BACKENDS.iter().map(|&b| path(8, b)).collect();
    let frames = converged(&scene, W, H, &runs);
    let base = &frames[2]; // compute
    for (f, b) in frames.iter().zip(common::BACKENDS).take(2) {
        let (mut sum_diff, mut sum, mut over) = (0.0f64, 0.0f64, 0);
        for (a, c) in f.hdr.iter().zip(&base.hdr) {
            sum_diff += (a - c).abs() as f64;
            sum += c.abs() as f64;
            over += ((a - c).abs() > 0.01 * c.abs().max(1e-3)) as u32;
        }
        let share = over as f64 / f.hdr.len() as f64;
        println!(
            "{b:?} vs compute: mean |difference| / mean {:.2e}, {:.3}% of values over 1%",
            sum_diff / sum,
            share * 100.0
        );
        // Measured on lavapipe: 3e-7 and none. A path that meets a different
        // triangle on one traversal (an edge, a grazing hit) goes elsewhere.
        assert!(sum_diff / sum < 1e-3, "{b:?} vs compute: {}", sum_diff / sum);
        assert!(share < 0.01, "{b:?} vs compute: {:.3}% of values differ by over 1%", share * 100.0);
    }
}

#[test]
fn path_mode_usage_errors_name_the_flag() {
    let run = |args: &[&str]| {
        let out = common::tiny_render_cmd().args(args).output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).to_string())
    };
    let out = common::out_dir().join("path_usage.png");
    let out = out.to_str().unwrap();
    let (code, err) = run(&["--samples", "4", "--out", out]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--samples") && err.contains("--mode path"), "{err}");
    let (code, err) = run(&["--mode", "path", "--aa", "edge", "--out", out]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--aa"), "{err}");
    let (code, err) = run(&["--mode", "path", "--samples", "0", "--out", out]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--samples"), "{err}");
    let (code, err) = run(&["--mode", "path", "--debug-view", "normal", "--out", out]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("--debug-view") && err.contains("--mode path"), "{err}");
    // And a path render works end to end, with its linear radiance.
    let hdr = common::out_dir().join("path_usage.hdr");
    let (code, err) =
        run(&["--mode", "path", "--samples", "4", "--out", out, "--hdr-out", hdr.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    assert!(hdr.exists());
}

/// A Lambert floor (albedo 0.5) lit only by an emissive 1 m square of
/// radiance 2 held 1 m above it (black, so nothing bounces back), seen from
/// straight above through a narrow view: below the square's centre the
/// floor reads rho / pi * E with E = 4 pi L F, F the form factor of a
/// differential area to the a x a rectangle above its corner,
/// F = (1/2pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))]
/// with X = Y = a/h = 0.5 (= 0.059862). The emitter is sampled as a light:
/// the mean is right (MIS with the BSDF samples that hit it) and the noise
/// at 16 paths is a fraction of what BSDF sampling alone gives (the square
/// covers a quarter of the cosine lobe: per path sd/mean ~ 1.8).
#[test]
fn emissive_surfaces_are_sampled_as_lights() {
    let toml = scene_toml([
        black_sky(),
        no_light(),
        camera([0.0, 0.5, 0.0], [0.0; 3]).up([0.0, 0.0, -1.0]).yfov(8),
        lambert("floor", [0.5; 3]).ior(1.0),
        emitter("lamp", [2.0; 3]),
        plane("floor", [40.0, 40.0]).material("floor"),
        plane("lamp", [1.0, 1.0]).at([0.0, 1.0, 0.0]).material("lamp"),
    ]);
    let scene = common::scene_from_toml("path_emissive_square", &toml);
    let frames = converged(&scene, W, H, &[path(16, Backend::Compute), path(256, Backend::Compute)]);
    let expected = 0.5 * 2.0 * common::rectangle_form_factor(1.0, -0.5, 0.5, -0.5, 0.5);
    let m = mean(&frames[1], 1, |_, _| true);
    let noisy = &frames[0];
    let m16 = mean(noisy, 1, |_, _| true);
    let rms = ((0..W * H).map(|i| (noisy.radiance(i % W, i / W)[1] as f64 - m16).powi(2)).sum::<f64>()
        / (W * H) as f64)
        .sqrt();
    println!(
        "floor below the lamp: {m:.5} (expected {expected:.5}); at 16 paths per pixel rms/mean {:.3}",
        rms / m16
    );
    assert!((m / expected - 1.0).abs() < 0.015, "floor {m}, expected {expected}");
    assert!(rms / m16 < 0.15, "per-pixel noise {} of the mean at 16 paths: is the lamp sampled?", rms / m16);
}

#[test]
fn volume_attenuation_follows_beer_lambert_in_both_modes() {
    let l = 0.5f32;
    let c = [0.5f32, 0.8, 1.0];
    let toml = scene_toml([
        environment([l, l, l]),
        no_light(),
        camera([0.0, 0.0, 4.0], [0.0; 3]).yfov(30),
        glass("tinted", 1.0).set("attenuation_color", shown3(c)).set("attenuation_distance", 1.0),
        cube("cube", 1.0).material("tinted"),
    ]);
    let scene = common::scene_from_toml("path_volume", &toml);
    let cam = &scene.cameras[0];
    let hybrid = RenderSettings { aa: AaMode::None, ..Default::default() };
    let frames = converged(&scene, W, H, &[path(16, Backend::Compute), hybrid]);
    for (f, what) in frames.iter().zip(["path", "hybrid"]) {
        let mut n = 0;
        for y in 0..H {
            for x in 0..W {
                let (o, d) = common::pixel_ray(cam, W, H, x, y);
                // In through the face z = 0.5, out through z = -0.5, well
                // inside both (the jittered paths stay on those faces).
                let (front, back) = (o + d * ((0.5 - o.z) / d.z), o + d * ((-0.5 - o.z) / d.z));
                if front.x.abs().max(front.y.abs()).max(back.x.abs()).max(back.y.abs()) > 0.4 {
                    continue;
                }
                let len = 1.0 / d.z.abs();
                let got = f.radiance(x, y);
                for k in 0..3 {
                    let want = l * c[k].powf(len);
                    assert!(
                        (got[k] / want - 1.0).abs() < 2e-3,
                        "{what}: pixel ({x}, {y}) channel {k}: {} vs Beer-Lambert {want}",
                        got[k]
                    );
                }
                n += 1;
            }
        }
        println!("{what}: {n} pixels through the cube follow Beer-Lambert");
        assert!(n > 30, "{what}: only {n} pixels through the cube");
    }
}
