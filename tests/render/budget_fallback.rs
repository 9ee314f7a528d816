//! What the effects the ray-tracing budget leaves out show (`--fallback`,
//! render/budget's Fallback): with the raster fallback a mirror left out
//! reflects the environment exactly as the traced reflection does where it
//! sees only sky, and a directional light's shadow comes from a shadow map
//! covering the traced shadow's pixels (IoU >= 0.9); point lights stay
//! unshadowed; the `shadow_map` pass records only when a shadow bit is
//! off. With `none` nothing is reflected or shadowed.
use crate::common;

use common::toml::*;

use hybrid_rt::image_diff::diff_stats;
use hybrid_rt::render::budget::{BudgetSettings, Fallback};
use hybrid_rt::render::shading::Effects;
use hybrid_rt::render::{AmbientMode, RenderSettings, Renderer};

const W: u32 = 96;
const H: u32 = 54;

fn zero_budget(base: BudgetSettings, fallback: Fallback) -> Option<BudgetSettings> {
    Some(BudgetSettings { fallback, ..base })
}

/// A lone mirror sphere under a graded sky: its reflection rays all miss,
/// so the traced reflection is exactly the environment in the mirror
/// direction.
fn mirror_sphere_scene() -> String {
    // Gradients in both directions: a wrong direction or weight shows.
    let map = common::write_hdr("fallback_sky", 32, 16, |x, y| {
        [0.2 + x as f32 / 16.0, 0.1 + y as f32 / 8.0, 0.6 - y as f32 / 40.0]
    });
    scene_toml([
        environment_hdr(map.display()),
        camera([0.0, 0.3, 3.0], [0.0; 3]).yfov(45),
        no_light(),
        mirror("mirror", [0.9, 0.8, 0.7]),
        sphere("ball", 0.8).material("mirror"),
    ])
}

#[test]
fn a_mirror_left_out_reflects_the_sky_as_the_traced_one_does_on_every_backend() {
    let scene = common::scene_from_toml("fallback_mirror_sphere", &mirror_sphere_scene());
    for backend in common::BACKENDS {
        let full = RenderSettings { backend, ambient: AmbientMode::Sh, ..Default::default() };
        let traced = common::render_scene(&scene, W, H, &full);
        let modes = [BudgetSettings::paper(0.0), BudgetSettings::effects(0.0)];
        for base in modes {
            let with = |fallback| RenderSettings { budget: zero_budget(base, fallback), ..full };
            let raster = common::render_scene(&scene, W, H, &with(Fallback::Raster));
            let none = common::render_scene(&scene, W, H, &with(Fallback::None));
            // The same weight times the same environment lookup: equal up
            // to one 8-bit step (float rounding of the two code paths).
            let (max_raster, _) = diff_stats(&traced.rgb8(), &raster.rgb8(), 3, 1);
            // Without a fallback the mirror is shaded as raster-only: the
            // split-sum environment (gpu/env_prefilter.rs, level 0 at 256x128)
            // stands in for the reflection, so the sky stays in it; before it
            // the sphere lost its reflection (12% of the frame off by > 8).
            let (max_none, share_none) = diff_stats(&traced.rgb8(), &none.rgb8(), 3, 8);
            eprintln!(
                "{backend:?} {:?}: budget 0 raster fallback vs traced max {max_raster}; none max {max_none}, {:.2}% over 8",
                base.mode,
                share_none * 100.0
            );
            assert!(max_raster <= 1, "{backend:?} {:?}: raster fallback differs by {max_raster}", base.mode);
            assert!(
                share_none < 0.01,
                "{backend:?}: --fallback none lost the sky in the mirror ({share_none})"
            );
        }
    }
}

/// A sphere above a ground plane, lit by one light; a dim grey sky so
/// shadowed ground is near black.
fn sphere_over_ground(light: Block) -> String {
    scene_toml([
        environment([0.05, 0.05, 0.05]),
        camera([0.0, 4.0, 5.0], [0.0; 3]).yfov(50),
        light,
        lambert("ground", [0.8, 0.8, 0.8]),
        lambert("red", [0.8, 0.1, 0.1]),
        plane("ground", [20.0, 20.0]).material("ground"),
        sphere("ball", 0.7).at([0.0, 1.0, 0.0]).material("red"),
    ])
}

fn sun() -> Block {
    directional([-0.4, -1.0, -0.3], 3.0)
}

const SW: u32 = 160;
const SH: u32 = 90;

/// Per pixel: whether its camera ray reaches the ground plane (y = 0,
/// |x|, |z| < 10) before the sphere, and the ground there is in shadow: its
/// HDR luminance under half of `unshadowed`'s (the same scene rendered
/// without shadows; a shadowed pixel keeps only the ambient light, under a
/// tenth of the lit value here).
fn ground_shadow_mask(
    scene: &hybrid_rt::scene::Scene,
    frame: &hybrid_rt::render::FrameOutput,
    unshadowed: &hybrid_rt::render::FrameOutput,
) -> Vec<bool> {
    let cam = &scene.cameras[0];
    let (centre, r) = (glam::Vec3::new(0.0, 1.0, 0.0), 0.7f32);
    let lum = |f: &hybrid_rt::render::FrameOutput, i: usize| {
        let p = &f.hdr[i * 4..i * 4 + 3];
        0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
    };
    (0..SW * SH)
        .map(|i| {
            let (x, y) = (i % SW, i / SW);
            let (o, d) = common::pixel_ray(cam, SW, SH, x, y);
            // Ground hit, and no sphere hit (closer) on the way.
            let t_ground = if d.y < -1e-4 { -o.y / d.y } else { return false };
            let g = o + d * t_ground;
            let oc = o - centre;
            let (b, c) = (oc.dot(d), oc.dot(oc) - r * r);
            let disc = b * b - c;
            if g.x.abs() > 9.9 || g.z.abs() > 9.9 || (disc > 0.0 && -b - disc.sqrt() < t_ground) {
                return false;
            }
            lum(frame, i as usize) < 0.5 * lum(unshadowed, i as usize)
        })
        .collect()
}

fn iou(a: &[bool], b: &[bool]) -> f64 {
    let inter = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let union = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    inter as f64 / union.max(1) as f64
}

/// A spot light above and beside the sphere, its cone over the ground
/// (the perspective shadow map).
fn spot_light() -> Block {
    spot([1.0, 4.0, 0.8], [-0.25, -1.0, -0.2], 40.0).cones(30.0, 40.0)
}

#[test]
fn a_shadow_left_out_falls_back_to_a_shadow_map_matching_the_traced_one() {
    let sun = common::scene_from_toml("fallback_sun_shadow", &sphere_over_ground(sun()));
    let spot = common::scene_from_toml("fallback_spot_shadow", &sphere_over_ground(spot_light()));
    // The spot's map on one backend: the maps do not depend on it.
    let cases =
        common::BACKENDS.map(|b| (b, &sun, "sun")).into_iter().chain([(common::BACKENDS[2], &spot, "spot")]);
    for (backend, scene, light) in cases {
        let full = RenderSettings { backend, ambient: AmbientMode::Sh, ..Default::default() };
        let with =
            |fallback| RenderSettings { budget: zero_budget(BudgetSettings::paper(0.0), fallback), ..full };
        let flat = RenderSettings { effects: Effects { shadows: false, ..full.effects }, ..full };
        let unshadowed = common::render_scene(scene, SW, SH, &flat);
        let mask = |s: &RenderSettings| {
            ground_shadow_mask(scene, &common::render_scene(scene, SW, SH, s), &unshadowed)
        };
        let traced = mask(&full);
        let raster = mask(&with(Fallback::Raster));
        let none = mask(&with(Fallback::None));
        let count = |m: &[bool]| m.iter().filter(|&&d| d).count();
        let score = iou(&traced, &raster);
        eprintln!(
            "{backend:?} {light}: shadowed ground pixels traced {}, shadow map {}, none {}; IoU {score:.3}",
            count(&traced),
            count(&raster),
            count(&none)
        );
        // The shadow is there to compare: ~1% of the frame (143 pixels).
        assert!(count(&traced) > 100, "{backend:?} {light}: the traced shadow is missing");
        assert_eq!(count(&none), 0, "{backend:?} {light}: --fallback none drew a shadow");
        assert!(
            score >= 0.9,
            "{backend:?} {light}: shadow-map shadow IoU {score:.3} < 0.9 with the traced one"
        );
    }
}

#[test]
fn point_lights_stay_unshadowed_in_the_fallback() {
    let lamp = point([0.5, 3.0, 0.5], 30.0);
    let scene = common::scene_from_toml("fallback_point_shadow", &sphere_over_ground(lamp));
    let full =
        RenderSettings { backend: common::BACKENDS[2], ambient: AmbientMode::Sh, ..Default::default() };
    let with_raster =
        RenderSettings { budget: zero_budget(BudgetSettings::paper(0.0), Fallback::Raster), ..full };
    let flat = RenderSettings { effects: Effects { shadows: false, ..full.effects }, ..full };
    let unshadowed = common::render_scene(&scene, SW, SH, &flat);
    let traced_frame = common::render_scene(&scene, SW, SH, &full);
    let raster_frame = common::render_scene(&scene, SW, SH, &with_raster);
    let traced = ground_shadow_mask(&scene, &traced_frame, &unshadowed);
    let raster = ground_shadow_mask(&scene, &raster_frame, &unshadowed);
    let count = |m: &[bool]| m.iter().filter(|&&d| d).count();
    eprintln!("point light: shadowed ground pixels traced {}, fallback {}", count(&traced), count(&raster));
    // (377 pixels: the lamp is close, its shadow larger than the sun's.)
    assert!(count(&traced) > 100, "the traced point-light shadow is missing");
    assert_eq!(count(&raster), 0, "the fallback shadowed a point light (documented as unshadowed)");
    assert!(
        !raster_frame.timings.iter().any(|(p, _)| *p == "shadow_map"),
        "a point light needs no shadow map"
    );
}

#[test]
fn the_shadow_map_pass_records_only_when_a_shadow_bit_is_off() {
    let scene = common::scene_from_toml("fallback_sun_shadow", &sphere_over_ground(sun()));
    let backend = common::BACKENDS[2];
    // Under synchronization validation: the pass's own layout transitions
    // and the lookups in `direct` are ordered.
    let ctx = common::sync_validated_context();
    let records = |budget: f64, fallback| {
        let settings = RenderSettings {
            backend,
            budget: zero_budget(BudgetSettings::paper(budget), fallback),
            ..Default::default()
        };
        let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
        let frame = r.render(&ctx, &scene, &scene.cameras[0], &settings).unwrap();
        let timed: Vec<_> = frame.timings.iter().map(|(n, _)| *n).filter(|n| *n != "readback").collect();
        assert_eq!(timed, r.pass_names(), "the frame's pass list is what it timed");
        r.destroy(&ctx);
        timed.contains(&"shadow_map")
    };
    assert!(records(0.0, Fallback::Raster), "budget 0: the shadow map is needed and not recorded");
    assert!(!records(f64::INFINITY, Fallback::Raster), "budget inf: every shadow traced, yet a shadow map");
    assert!(!records(0.0, Fallback::None), "--fallback none rendered a shadow map");
    common::assert_validation_clean(&ctx);
}
