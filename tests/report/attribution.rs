//! The report's attribution terms (pass `terms`, glsl/passes/terms.glsl,
//! report/attribution.rs): the hybrid frame with one term of light
//! transport supplied by the path tracer.
//!
//! - Diffuse visibility, analytic: a white floor with IOR 1 (no specular
//!   at all: f0 = 0, so the floor is pure Lambert) under a black sphere
//!   (radius r, centre at height d; black: it reflects nothing) in a
//!   constant environment L, no light. The hybrid shades the floor with the
//!   unshadowed SH ambient (ratio 1 to the open floor); with the term
//!   supplied the floor's radiance over the unoccluded value is
//!   1 - r^2 d / D^3 (tests/report/reference.rs has the derivation) within the
//!   same Bernoulli bound. The environment-specular term changes nothing
//!   there (no specular lobe), and every term together gives the
//!   visibility term's image (the same rays; nothing else carries light).
//! - Caustics: a clear glass sphere over the floor under a sun from
//!   straight above, a black sky. The hybrid's shadow ray passes the glass
//!   (transmittance 1), so the floor under the sphere is lit as in the
//!   open; the path-traced truth has no light from a delta sun through
//!   glass there. Supplying the caustics term removes it: what is left
//!   under the sphere is the sunlit floor seen through the glass, under a
//!   fifth of the hybrid's value. All three backends trace the same rays:
//!   they agree within 1e-3 relative mean difference (the opaque shadow
//!   rays of the RT pipeline's any-hit shader included).
//! - Without the terms no pass and no target exist; the terms refuse a
//!   debug view.
use crate::common;

use common::toml::*;

use common::Bench;
use glam::Vec3;
use hybrid_rt::app::EnvOverrides;
use hybrid_rt::gpu::shared::{TERMS_SAMPLES_PER_FRAME, TERM_CAUSTICS, TERM_ENV_SPECULAR, TERM_VISIBILITY};
use hybrid_rt::render::shading::Backend;
use hybrid_rt::render::{AmbientMode, DebugView, FrameOutput, RenderSettings};
use hybrid_rt::report::attribution::all_terms;
use hybrid_rt::scene::{Camera, EnvLayout, Scene};

/// The hybrid frame these closed forms are about: the unshadowed SH ambient (the traced one's own checks
/// are tests/render/ambient_visibility.rs).
fn sh() -> RenderSettings {
    RenderSettings { ambient: AmbientMode::Sh, ..Default::default() }
}

const L: f32 = 0.5;

/// A floor and a sphere of radius 0.5 centred 1.0 above the origin, seen
/// from above and aside; `sun` a directional light straight down.
fn scene(name: &str, sphere_material: &str, sun: f32, sky: f32) -> Scene {
    let toml = scene_toml([
        camera([0.0, 1.6, 2.4], [0.0; 3]).yfov(40),
        directional([0.0, -1.0, 0.0], shown(sun)),
        lambert("floor", [0.8; 3]).ior(1.0),
        lambert("black", [0.0; 3]).ior(1.0),
        glass("glass", 1.5),
        plane("ground", [40.0, 40.0]).material("floor"),
        sphere("ball", 0.5).at([0.0, 1.0, 0.0]).material(sphere_material),
    ]);
    let map = common::write_hdr(&format!("{name}_sky"), 32, 16, |_, _| [sky; 3]);
    let mut scene = common::scene_from_toml(name, &toml);
    EnvOverrides { map: Some((map, EnvLayout::Equirect)), ..Default::default() }.apply(&mut scene).unwrap();
    scene
}

/// The frame with `terms` supplied, `samples` per pixel, from scratch.
fn with_terms(
    b: &mut Bench,
    scene: &Scene,
    cam: &Camera,
    terms: u32,
    samples: u32,
    backend: Backend,
) -> FrameOutput {
    let settings = RenderSettings { terms, backend, ..sh() };
    b.renderer.reset_reference();
    let frames = samples.div_ceil(TERMS_SAMPLES_PER_FRAME);
    let mut out = None;
    for _ in 0..frames {
        out = Some(b.frame(scene, cam, &settings));
    }
    assert_eq!(b.renderer.reference_frames(), frames, "the accumulation restarted");
    assert!(b.renderer.pass_names().contains(&"terms"), "{:?}", b.renderer.pass_names());
    out.unwrap()
}

/// Mean over `pixels` of a / b in red.
fn mean_ratio(a: &FrameOutput, b: &FrameOutput, pixels: &[(usize, Vec3)]) -> f64 {
    pixels.iter().map(|(i, _)| (a.hdr[i * 4] / b.hdr[i * 4]) as f64).sum::<f64>() / pixels.len() as f64
}

#[test]
fn visibility_term_matches_the_analytic_occlusion() {
    let (w, h) = (96, 54);
    let scene = scene("attribution_visibility", "black", 0.0, L);
    let cam = scene.cameras[0].clone();
    let mut b = Bench::new(&scene, w, h);
    let hybrid = b.frame(&scene, &cam, &sh());
    // Leave-out: without terms no pass and no accumulation target.
    assert!(!b.renderer.pass_names().contains(&"terms"), "{:?}", b.renderer.pass_names());
    assert!(b.renderer.targets().describe().iter().all(|(n, _)| !n.contains("terms")));
    let debug =
        RenderSettings { terms: TERM_VISIBILITY, debug_view: DebugView::Normal, ..Default::default() };
    let err = b.renderer.render(&b.ctx, &scene, &cam, &debug).err().expect("terms in a debug view");
    assert!(format!("{err:#}").contains("debug view"), "{err:#}");

    let pixels = common::ground_pixels(&cam, w, h, 0.3);
    assert!(pixels.len() >= 20, "only {} floor pixels near the origin", pixels.len());
    let (r, d) = (0.5f64, 1.0f64);
    let expected = pixels
        .iter()
        .map(|(_, p)| 1.0 - r * r * d / (p.length_squared() as f64 + d * d).sqrt().powi(3))
        .sum::<f64>()
        / pixels.len() as f64;
    // The hybrid frame: the floor as in the open, 0.8 L.
    let open = pixels.iter().map(|(i, _)| hybrid.hdr[i * 4] as f64 / (0.8 * L as f64)).sum::<f64>()
        / pixels.len() as f64;
    assert!((open - 1.0).abs() < 0.01, "the hybrid floor over 0.8 L: {open}");

    let samples = 512;
    let vis = with_terms(&mut b, &scene, &cam, TERM_VISIBILITY, samples, Backend::Auto);
    let ratio = mean_ratio(&vis, &hybrid, &pixels);
    let bound = 5.0 * 0.5 / (samples as f64 * pixels.len() as f64).sqrt() + 0.005;
    println!(
        "{} pixels: with diffuse visibility / hybrid {ratio:.4}, analytic {expected:.4}, bound {bound:.4}",
        pixels.len()
    );
    assert!((ratio - expected).abs() <= bound, "visibility: {ratio} vs analytic {expected} (bound {bound})");

    let spec = with_terms(&mut b, &scene, &cam, TERM_ENV_SPECULAR, 8, Backend::Auto);
    let worst = spec
        .hdr
        .iter()
        .zip(&hybrid.hdr)
        .map(|(a, c)| (a - c).abs() / c.abs().max(1e-3))
        .fold(0.0f32, f32::max);
    assert!(worst <= 1e-4, "the specular term changed a scene without specular lobes: {worst}");

    let all = with_terms(&mut b, &scene, &cam, all_terms(), samples, Backend::Auto);
    let worst =
        all.hdr.iter().zip(&vis.hdr).map(|(a, c)| (a - c).abs() / c.abs().max(1e-3)).fold(0.0f32, f32::max);
    assert!(worst <= 1e-4, "every term vs visibility alone, where nothing else carries light: {worst}");
    b.finish();
}

#[test]
fn caustics_term_removes_sunlight_straight_through_glass_on_every_backend() {
    let (w, h) = (64, 36);
    let scene = scene("attribution_caustics", "glass", 3.0, 0.0);
    let cam = scene.cameras[0].clone();
    let mut b = Bench::new(&scene, w, h);
    // Under the sphere (the sun is straight above): the floor within 0.3.
    let pixels = common::ground_pixels(&cam, w, h, 0.3);
    assert!(pixels.len() >= 10, "only {} floor pixels under the sphere", pixels.len());
    let mut means = Vec::new();
    for backend in common::BACKENDS {
        let hybrid = b.frame(&scene, &cam, &RenderSettings { backend, ..sh() });
        let lit: f64 =
            pixels.iter().map(|(i, _)| hybrid.hdr[i * 4] as f64).sum::<f64>() / pixels.len() as f64;
        // The sun at 3 on a 0.8 Lambert floor, straight through the glass.
        assert!((lit - 3.0 * 0.8 / std::f64::consts::PI).abs() < 0.05, "{backend:?}: hybrid floor {lit}");
        let c = with_terms(&mut b, &scene, &cam, TERM_CAUSTICS, 16, backend);
        let left = mean_ratio(&c, &hybrid, &pixels);
        println!("{backend:?}: under the glass with caustics supplied / hybrid {left:.4}");
        assert!(left < 0.2, "{backend:?}: the sunlight through glass stays: {left}");
        means.push(pixels.iter().map(|(i, _)| c.hdr[i * 4] as f64).sum::<f64>() / pixels.len() as f64);
    }
    for (m, backend) in means.iter().zip(common::BACKENDS) {
        let rel = (m - means[0]).abs() / means[0].abs().max(1e-6);
        assert!(rel <= 1e-3, "{backend:?} {m} vs {:?} {}: {rel}", common::BACKENDS[0], means[0]);
    }
    b.finish();
}

/// A sky with a horizon and a small hot sun at `sun_u` (18° up), 64 x 32: what a split sum gets wrong
/// first.
fn sunset_sky(name: &str, sun_u: f32) -> std::path::PathBuf {
    common::write_hdr(name, 64, 32, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / 64.0, (y as f32 + 0.5) / 32.0);
        if (u - sun_u).abs() < 0.02 && (v - 0.4).abs() < 0.03 {
            [60.0, 45.0, 25.0]
        } else if v < 0.5 {
            [0.4 + 0.6 * v, 0.5 + 0.4 * v, 1.0 - 0.5 * v]
        } else {
            [0.25, 0.2, 0.15]
        }
    })
}

/// Environment specular, against the path tracer: two metal spheres (rough gold 0.45, the issue's
/// 0.68-of-the-truth case, and a rougher 0.8 steel) alone under a sky with a sun, no light. On a lone
/// convex sphere nothing occludes the environment, so the truth's environment-specular term (its
/// GGX lobe, sampled by visible normals, with the same multiple-scattering compensation) is what the
/// split sum approximates. Measured over each sphere's face (n.v > 0.5), per channel, hybrid / truth:
/// - sun in front of the spheres (behind the camera): within 3 % (measured 0.987-1.009; the
///   sampling noise is under 1 % at 256 samples, the prefilter's own error 2-3 %). The former
///   f0 x SH ambient (no lobe: the sky's mean about the normal) gave 1.15 on the gold here.
/// - sun behind them, near their silhouettes: the split sum leaks light from below the surface's
///   horizon (its lobe is prefiltered about the reflection direction as if n = v, so part of it lies
///   behind the surface); measured 1.03-1.06 (gold) and up to 1.15 (steel), held under 1.2.
#[test]
fn env_specular_matches_the_path_traced_lobe_on_rough_metals() {
    let (w, h) = (96, 54);
    for (sun_u, bound) in [(0.85f32, 0.03f64), (0.3, 0.2)] {
        let sky = sunset_sky(&format!("attribution_env_specular_sky_{sun_u}"), sun_u);
        let toml = scene_toml([
            environment_hdr(sky.display()),
            camera([0.0, 0.0, 3.2], [0.0; 3]).yfov(40),
            no_light(),
            material("gold").base([1.0, 0.78, 0.34]).metallic(1.0).roughness(0.45),
            material("steel").base([0.6, 0.62, 0.65]).metallic(1.0).roughness(0.8),
            sphere("gold ball", 0.5).at([-0.9, 0.0, 0.0]).material("gold"),
            sphere("steel ball", 0.5).at([0.9, 0.0, 0.0]).material("steel"),
        ]);
        let scene = common::scene_from_toml("attribution_env_specular", &toml);
        let cam = scene.cameras[0].clone();
        let mut b = Bench::new(&scene, w, h);
        // The split sum alone: the glossy pass (gold is in its range) corrects it where the lobe meets
        // geometry, and the attribution measures the frame without that correction.
        let mut split_sum = sh();
        split_sum.effects.reflections = false;
        let hybrid = b.frame(&scene, &cam, &split_sum);
        let truth = with_terms(&mut b, &scene, &cam, TERM_ENV_SPECULAR, 256, Backend::Auto);
        for (name, x_centre) in [("gold", -0.9f32), ("steel", 0.9)] {
            let pixels = sphere_face_pixels(&cam, w, h, Vec3::new(x_centre, 0.0, 0.0));
            assert!(pixels.len() >= 100, "{name}: {} pixels", pixels.len());
            for ch in 0..3 {
                let sum = |f: &FrameOutput| pixels.iter().map(|i| f.hdr[i * 4 + ch] as f64).sum::<f64>();
                let ratio = sum(&hybrid) / sum(&truth);
                println!("sun at u {sun_u}: {name} channel {ch}: hybrid / path-traced {ratio:.4}");
                assert!((ratio - 1.0).abs() < bound, "sun at u {sun_u}: {name} channel {ch}: {ratio}");
            }
        }
        b.finish();
    }
}

/// Pixels whose camera ray meets the sphere of radius 0.5 at `centre` where its normal faces the
/// viewer (n.v > 0.5).
fn sphere_face_pixels(cam: &Camera, w: u32, h: u32, centre: Vec3) -> Vec<usize> {
    let mut pixels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (o, d) = common::pixel_ray(cam, w, h, x, y);
            let oc = o - centre;
            let (bq, c) = (oc.dot(d), oc.length_squared() - 0.25);
            let disc = bq * bq - c;
            if disc > 0.0 && (oc + d * (-bq - disc.sqrt())).normalize().dot(-d) > 0.5 {
                pixels.push((y * w + x) as usize);
            }
        }
    }
    pixels
}
