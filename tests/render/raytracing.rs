//! Secondary rays from the G-buffer (ray-query backend), checked against
//! closed-form answers on lavapipe with validation on.
#![allow(clippy::needless_range_loop)] // per-channel loops read clearer with indices
use crate::common;

use common::scenes::*;
use common::toml::*;

use glam::Vec3;
use hybrid_rt::render::shading::{AaMode, Effects, Mode};
use hybrid_rt::render::{DebugView, FrameOutput, RenderSettings, Renderer};

const W: u32 = 160;
const H: u32 = 90;

/// The closed-form checks and the golden probe shading, before
/// anti-aliasing (tests/render/antialias.rs tests the filters).
fn settings() -> RenderSettings {
    RenderSettings { aa: AaMode::None, ..Default::default() }
}

/// Per pixel of the unscaled shadow scene: None where the camera sees the
/// occluder (or close to it), else (ground point, inside the shadow square).
fn shadow_prediction(scene: &hybrid_rt::scene::Scene) -> Vec<Option<(Vec3, bool)>> {
    let cam = &scene.cameras[0];
    let mut out = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let (o, d) = common::pixel_ray(cam, W, H, x, y);
            let occ = o + d * ((2.0 - o.y) / d.y);
            if occ.x.abs() <= 0.6 && occ.z.abs() <= 0.6 {
                out.push(None);
                continue;
            }
            let g = o + d * (-o.y / d.y);
            out.push(Some((g, g.x.abs() <= 1.0 && g.z.abs() <= 1.0)));
        }
    }
    out
}

/// Unshadowed ground radiance at `g` (Lambert, albedo 0.8, 50 cd at (0,4,0)).
fn lit_radiance(g: Vec3) -> f32 {
    let d = Vec3::new(0.0, 4.0, 0.0) - g;
    0.8 / std::f32::consts::PI * 50.0 * (d.y / d.length()) / d.length_squared()
}

/// True when a pixel's predicted class differs from a neighbour's: the
/// shadow border, where one pixel of disagreement is allowed.
fn on_border(pred: &[Option<(Vec3, bool)>], x: u32, y: u32) -> bool {
    let me = pred[(y * W + x) as usize].map(|p| p.1);
    for dy in -1i32..=1 {
        for dx in -1i32..=1 {
            let (nx, ny) = (x as i32 + dx, y as i32 + dy);
            if nx < 0 || ny < 0 || nx >= W as i32 || ny >= H as i32 {
                continue;
            }
            if pred[(ny as u32 * W + nx as u32) as usize].map(|p| p.1) != me {
                return true;
            }
        }
    }
    false
}

/// Compares the rendered shadow with the projected square; returns the
/// number of shadowed pixels checked.
fn check_square_shadow(frame: &FrameOutput, pred: &[Option<(Vec3, bool)>], what: &str) -> usize {
    let (mut shadowed, mut wrong) = (0, Vec::new());
    for y in 0..H {
        for x in 0..W {
            let Some((g, inside)) = pred[(y * W + x) as usize] else { continue };
            if on_border(pred, x, y) {
                continue;
            }
            let expected = lit_radiance(g);
            let got = frame.radiance(x, y)[1];
            if inside {
                shadowed += 1;
                // No light leaking into the umbra.
                if got > 0.01 * expected {
                    wrong.push((x, y, got, 0.0));
                }
            } else if (got - expected).abs() > 0.02 * expected {
                // No acne: lit ground within 2% of the closed form.
                wrong.push((x, y, got, expected));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "{what}: {} wrong pixels, first {:?}",
        wrong.len(),
        &wrong[..wrong.len().min(5)]
    );
    assert!(shadowed > 100, "{what}: only {shadowed} shadowed pixels checked");
    shadowed
}

#[test]
fn square_occluder_casts_its_projected_shadow() {
    let scene = common::scene_from_toml("shadow", &shadow_scene(Frame::IDENTITY, opaque_occluder()));
    let pred = shadow_prediction(&scene);
    let frame = common::render_scene(&scene, W, H, &settings());
    let n = check_square_shadow(&frame, &pred, "origin");
    eprintln!("shadow matches the projected square: {n} umbra pixels checked");

    // The same test fails when shadows are off: it can tell.
    let unshadowed =
        common::render_scene(&scene, W, H, &RenderSettings { effects: Effects::NONE, ..settings() });
    let leaked = pred
        .iter()
        .enumerate()
        .filter(|(i, p)| p.is_some_and(|(_, inside)| inside) && unshadowed.hdr[i * 4 + 1] > 0.1)
        .count();
    assert!(leaked > 100);
}

/// Self-intersection offsets (Wächter–Binder) on every backend: the shadow
/// scene far from the origin, tilted (so the ground is no axis plane and
/// every coordinate's offset matters), and at extreme scales. The camera
/// moves with the scene, so the prediction of the untransformed scene holds.
/// Shadow acne shows up as lit pixels off by > 2%, leaks as umbra light.
#[test]
fn shadow_is_robust_far_from_origin_tilted_and_at_extreme_scales_on_every_backend() {
    let base = common::scene_from_toml("shadow_base", &shadow_scene(Frame::IDENTITY, opaque_occluder()));
    let pred = shadow_prediction(&base);
    let tilt = Vec3::new(23.0, 41.0, -17.0);
    let frames = [
        Frame::at(1.0, Vec3::new(1e4, 1e4, -1e4)),
        Frame::at(1.0, Vec3::new(1e5, 0.0, 1e5)),
        Frame { tilt_deg: tilt, ..Frame::at(1.0, Vec3::new(1e5, -3e4, 1e5)) },
        Frame { tilt_deg: tilt, ..Frame::at(1e-3, Vec3::ZERO) },
        Frame { tilt_deg: tilt, ..Frame::at(1e3, Vec3::ZERO) },
        // Within 1/32 of the origin every coordinate takes the small-float
        // branch of the offset.
        Frame { tilt_deg: tilt, ..Frame::at(2e-3, Vec3::splat(1e-3)) },
    ];
    for backend in common::BACKENDS {
        for f in frames {
            let scene = common::scene_from_toml("shadow_far", &shadow_scene(f, opaque_occluder()));
            let frame = common::render_scene(&scene, W, H, &RenderSettings { backend, ..settings() });
            check_square_shadow(&frame, &pred, &format!("{backend:?} {f:?}"));
        }
    }
}

#[test]
fn colored_glass_pane_casts_a_colored_shadow() {
    let tint = [1.0f32, 0.3, 0.1];
    let glass = glass_occluder(tint);
    let scene = common::scene_from_toml("glass_shadow", &shadow_scene(Frame::IDENTITY, glass));
    let pred = shadow_prediction(&scene);
    let frame = common::render_scene(&scene, W, H, &settings());
    let mut checked = 0;
    for y in 0..H {
        for x in 0..W {
            let Some((g, true)) = pred[(y * W + x) as usize] else { continue };
            if on_border(&pred, x, y) {
                continue;
            }
            let l = frame.radiance(x, y);
            let e = lit_radiance(g);
            for c in 0..3 {
                let ratio = l[c] / e;
                assert!(
                    (ratio - tint[c]).abs() < 0.02,
                    "pixel ({x},{y}) channel {c}: transmittance {ratio}, expected {}",
                    tint[c]
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 100, "only {checked} pixels in the coloured shadow");
}

#[test]
fn mirror_shows_the_wall_times_f0() {
    let f0 = [0.9f32, 0.6, 0.3];
    let wall = [0.8f32, 0.5, 0.25];
    let scene = common::scene_from_toml("mirror", &mirror_scene(f0, wall));
    let frame = common::render_scene(&scene, W, H, &settings());
    for (x, y) in [(W / 2, H / 2), (10, 10), (W - 10, H - 10), (30, 60)] {
        let l = frame.radiance(x, y);
        for c in 0..3 {
            let expected = f0[c] * wall[c];
            assert!(
                (l[c] - expected).abs() <= 0.01 * expected,
                "pixel ({x},{y}) c{c}: {} vs {expected}",
                l[c]
            );
        }
    }
    // Without reflections the mirror shows no wall at all.
    let off = common::render_scene(
        &scene,
        W,
        H,
        &RenderSettings { effects: Effects { reflections: false, ..Effects::default() }, ..settings() },
    );
    assert!(off.radiance(W / 2, H / 2)[0] < 0.01);
}

/// A red cube and a green ball, both glowing (and rough), under a blue sky, no light;
/// a glass material of index `ior` for `extra` (more blocks) to use.
fn backdrop(ior: f32, extra: impl IntoIterator<Item = Block>) -> String {
    let blocks = [
        environment([0.2, 0.3, 0.5]),
        camera([0.0, 1.0, 5.0], [0.0, 1.0, 0.0]).yfov(50),
        no_light(),
        // Rough: glossy reflections are traced at primary hits only, so a glossy surface seen through
        // the slab would lose its lobe's occlusion; IOR 1 (no specular lobe): the emitters' light on
        // each other is shaded at primary hits only, not at the hits seen through the slab. This is
        // about the slab.
        emitter("red", [1.0, 0.1, 0.1]).roughness(1.0).ior(1.0),
        emitter("green", [0.1, 1.0, 0.2]).roughness(1.0).ior(1.0),
        glass("glass", ior),
        cube("a", 1.0).at([-1.0, 1.0, -2.0]).rot([20.0, 30.0, 0.0]).material("red"),
        sphere("b", 0.7).at([1.0, 1.3, -2.5]).material("green"),
    ];
    scene_toml(blocks.into_iter().chain(extra))
}

/// Glass with IOR 1 bends nothing and reflects nothing: the image behind a
/// slab of it, smooth or rough, is unchanged. A glass sphere of IOR 1.5 exercises total
/// internal reflection at grazing angles; nothing may become NaN.
#[test]
fn ior_one_slab_is_invisible_and_glass_sphere_stays_finite() {
    let without = common::scene_from_toml("backdrop", &backdrop(1.0, []));
    // Smooth, and rough past MIRROR_ROUGHNESS ("frosted": no reflection
    // branch, the refraction alone carries what is behind it).
    // The slab's glass, "glass" or "frosted", of index `ior`.
    let slab = |material, ior: f32| {
        backdrop(
            ior,
            [
                glass("frosted", ior).roughness(0.6),
                cube("slab", 1.0).scale([3.0, 2.0, 0.2]).at([0.0, 1.0, 1.0]).material(material),
            ],
        )
    };
    let a = common::render_scene(&without, W, H, &settings());
    for material in ["glass", "frosted"] {
        let b =
            common::render_scene(&common::scene_from_toml("slab", &slab(material, 1.0)), W, H, &settings());
        // The IOR-1 sphere's rule below, over the whole frame: no pixel off
        // by more than 2/255. A PSNR bound let a 5/255 shift behind the
        // slab (a quarter of the frame) pass.
        let (max, changed) = hybrid_rt::image_diff::diff_stats(&a.ldr, &b.ldr, 4, 2);
        eprintln!("IOR-1 {material} slab: max difference {max}/255, {changed:.5} of pixels over 2/255");
        assert!(
            max <= 2 && changed == 0.0,
            "IOR-1 {material} slab changed the image: max {max}/255, {:.3}% of pixels over 2/255",
            changed * 100.0
        );
    }
    // The objects' debug view: the slab covers a quarter of the frame (those
    // are the pixels the comparisons above are about).
    let ids = RenderSettings { debug_view: DebugView::Object, ..settings() };
    let with = common::scene_from_toml("slab", &slab("frosted", 1.0));
    let (_, covered) = hybrid_rt::image_diff::diff_stats(
        &common::render_scene(&without, W, H, &ids).ldr,
        &common::render_scene(&with, W, H, &ids).ldr,
        4,
        0,
    );
    eprintln!("the slab covers {:.1}% of the frame", covered * 100.0);
    assert!(covered > 0.15, "the slab covers only {:.2}% of the frame", covered * 100.0);

    let ball = sphere("ball", 1.0).slices(48, 24).at([0.0, 1.0, 1.0]).material("glass");
    // An IOR-1 sphere, seen edge-on at its silhouette too, where the angle
    // of incidence is grazing: no Fresnel reflection, no bending, no total
    // internal reflection (which rounding used to report there), no
    // specular highlight from Schlick's grazing term: invisible, on every
    // backend.
    // A glowing wall behind everything: a ray wrongly reflected at the
    // silhouette sees the (different) environment instead.
    let wall = [
        emitter("wall", [0.9, 0.8, 0.1]),
        plane("wall", [40.0, 40.0]).at([0.0, 0.0, -6.0]).rot([90.0, 0.0, 0.0]).material("wall"),
    ];
    let without_ball = common::scene_from_toml("ior1_backdrop", &backdrop(1.0, wall.clone()));
    let invisible =
        common::scene_from_toml("ior1_ball", &backdrop(1.0, wall.into_iter().chain([ball.clone()])));
    for backend in common::BACKENDS {
        let s = RenderSettings { backend, ..settings() };
        let a = common::render_scene(&without_ball, W, H, &s);
        let b = common::render_scene(&invisible, W, H, &s);
        let (max, changed) = hybrid_rt::image_diff::diff_stats(&a.ldr, &b.ldr, 4, 2);
        eprintln!("IOR-1 sphere on {backend:?}: max difference {max}/255, {changed:.5} of pixels over 2/255");
        assert!(max <= 2 && changed == 0.0, "{backend:?}: the IOR-1 sphere is visible: max {max}/255");
    }

    let glass = common::scene_from_toml("glass_ball", &backdrop(1.5, [ball]));
    let g = common::render_scene(&glass, W, H, &settings());
    let (max, changed) = hybrid_rt::image_diff::diff_stats(&a.ldr, &g.ldr, 4, 8);
    assert!(max > 30 && changed > 0.01, "the glass ball refracts nothing ({max}, {changed})");
}

/// Two facing mirrors: the recursion goes exactly as deep as `max_depth`
/// says. Counted secondary rays grow with the depth asked for (a cap at 8
/// whatever the flag says leaves 8 and 64 equal) and never pass one per
/// pixel and level (a mirror-only scene branches nowhere); no pixel hits
/// the per-pixel ray budget; each deeper image shows more inter-reflections.
/// One renderer changes the depth, the weight limit and ray counting between
/// frames: they are frame uniforms, so no pass is rebuilt or recompiled.
#[test]
fn facing_mirrors_terminate_at_max_depth() {
    let scene = common::scene_from_toml("mirrors", &facing_mirrors());
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let first = r.render(&ctx, &scene, &scene.cameras[0], &settings()).unwrap();
    assert!(first.cold, "the first frame compiles its passes");
    let mut frames = Vec::new();
    for depth in [2u32, 8, 64] {
        let t = std::time::Instant::now();
        let s = RenderSettings {
            effects: Effects { max_depth: depth, min_weight: 0.0, count_rays: true, ..Effects::default() },
            ..settings()
        };
        let f = r.render(&ctx, &scene, &scene.cameras[0], &s).unwrap();
        assert!(!f.cold, "max depth {depth}: the passes were rebuilt for a frame uniform");
        assert!(f.all_finite(), "NaN or Inf reached the frame");
        let secondary = f.ray_counts[2] as u64;
        eprintln!(
            "facing mirrors, max depth {depth}: {secondary} secondary rays ({:.2} per pixel), {:.2} s",
            secondary as f64 / (W * H) as f64,
            t.elapsed().as_secs_f64()
        );
        assert!(secondary <= (W * H) as u64 * depth as u64, "depth {depth}: {secondary} secondary rays");
        assert_eq!(f.truncated_pixels, 0, "depth {depth}: the per-pixel ray budget cut a mirror path");
        frames.push((depth, secondary, f));
    }
    // The weight limit, a frame uniform too: a 0.98 mirror's branch falls under 0.9 after 6 bounces.
    let s = RenderSettings {
        effects: Effects { max_depth: 64, min_weight: 0.9, count_rays: true, ..Effects::default() },
        ..settings()
    };
    let light = r.render(&ctx, &scene, &scene.cameras[0], &s).unwrap();
    assert!(!light.cold, "min weight 0.9: the passes were rebuilt for a frame uniform");
    let (cut, all) = (light.ray_counts[2] as u64, frames[2].1);
    assert!(cut < all, "min weight 0.9 traced no fewer secondary rays than 0 ({cut} vs {all})");
    r.destroy(&ctx);
    drop(ctx); // validation errors, teardown included, fail here
    for pair in frames.windows(2) {
        let ((d0, n0, a), (d1, n1, b)) = (&pair[0], &pair[1]);
        assert!(n1 > n0, "max depth {d1} traced no more rays than {d0} ({n1} vs {n0})");
        let (_, changed) = hybrid_rt::image_diff::diff_stats(&a.ldr, &b.ldr, 4, 2);
        assert!(changed > 0.001, "depth {d0} and {d1} look the same ({changed})");
    }
}

/// Pixels whose 3x3 neighbourhood sees more than one object (or background):
/// silhouettes, where hybrid and pure ray tracing may legitimately differ.
fn edge_mask(ids: &FrameOutput) -> Vec<bool> {
    let id = |x: i32, y: i32| {
        let i = ((y.clamp(0, H as i32 - 1) as u32 * W + x.clamp(0, W as i32 - 1) as u32) * 4) as usize;
        [ids.ldr[i], ids.ldr[i + 1], ids.ldr[i + 2]]
    };
    let mut keep = Vec::new();
    for y in 0..H as i32 {
        for x in 0..W as i32 {
            let me = id(x, y);
            let edge = (-1..=1).any(|dy| (-1..=1).any(|dx| id(x + dx, y + dy) != me));
            keep.push(!edge);
        }
    }
    keep
}

#[test]
fn hybrid_matches_pure_ray_tracing() {
    let scene = common::scene_from_toml("agreement", &agreement());
    let hybrid = common::render_scene(&scene, W, H, &settings());
    let rt = common::render_scene(&scene, W, H, &RenderSettings { mode: Mode::Rt, ..settings() });
    let ids =
        common::render_scene(&scene, W, H, &RenderSettings { debug_view: DebugView::Object, ..settings() });
    let mask = edge_mask(&ids);
    let psnr = hybrid_rt::image_diff::psnr_rgb8(&hybrid.ldr, &rt.ldr, 4, Some(&mask));
    let excluded = mask.iter().filter(|k| !**k).count() as f64 / mask.len() as f64;
    eprintln!(
        "hybrid vs pure RT: PSNR {psnr:.1} dB over non-edge pixels ({:.1}% edge pixels excluded)",
        excluded * 100.0
    );
    assert!(psnr >= 40.0, "hybrid and pure RT disagree: PSNR {psnr:.1} dB");
    common::check_golden(&hybrid, "spheres_hybrid_160x90");
}

/// A real asset with both: alpha-masked leaves and stems beside and behind a glass vase
/// (GlassVaseFlowers). Hybrid mode alpha-tests the leaves in the rasterizer, pure RT with ray queries
/// (with the rasterizer's uv gradients): only pixels where a cut-out or object edge passes may differ.
#[test]
fn hybrid_matches_pure_ray_tracing_on_cut_out_leaves_and_glass() {
    let path = common::shared_asset("gltf/GlassVaseFlowers/glTF/GlassVaseFlowers.gltf");
    let scene = hybrid_rt::scene::Scene::load(&path).unwrap();
    let s = RenderSettings { aa: AaMode::None, ..Default::default() };
    let hybrid = common::render_scene(&scene, W, H, &s);
    let rt = common::render_scene(&scene, W, H, &RenderSettings { mode: Mode::Rt, ..s });
    let ids = common::render_scene(&scene, W, H, &RenderSettings { debug_view: DebugView::Object, ..s });
    let mask = edge_mask(&ids);
    let (max_all, share) = hybrid_rt::image_diff::diff_stats(&hybrid.ldr, &rt.ldr, 4, 2);
    let inner = |f: &FrameOutput| -> Vec<u8> {
        f.ldr.chunks_exact(4).zip(&mask).filter(|(_, k)| **k).flat_map(|(p, _)| p.iter().copied()).collect()
    };
    let (max_inner, share_inner) = hybrid_rt::image_diff::diff_stats(&inner(&hybrid), &inner(&rt), 4, 2);
    eprintln!(
        "glass vase, hybrid vs pure RT: {:.3}% of pixels differ by > 2/255 (max {max_all}); away from object \
         edges {:.3}% (max {max_inner})",
        share * 100.0,
        share_inner * 100.0
    );
    assert!(share <= 0.005, "{:.3}% of pixels differ", share * 100.0);
    assert!(
        max_inner <= 2,
        "away from object edges: {:.3}% differ, max {max_inner}/255",
        share_inner * 100.0
    );
}

/// Snell's window: from inside a block of glass (IOR 1.5) looking up at its
/// top face, rays steeper than the critical angle (asin(1/1.5) = 41.8°)
/// leave and see a glowing ceiling; rays just past it are totally internally
/// reflected and stay trapped in the block until the depth limit: dark.
#[test]
fn total_internal_reflection_outside_the_critical_angle() {
    let scene = common::scene_from_toml(
        "snell_window",
        &scene_toml([
            black_sky(),
            camera([0.0; 3], [0.0, 1.0, 0.0]).yfov(120),
            no_light(),
            glass("glass", 1.5).double_sided(),
            emitter("ceiling", [1.0; 3]),
            cube("block", 20.0).material("glass"),
            plane("ceiling", [400.0, 400.0]).at([0.0, 11.0, 0.0]).rot([180.0, 0.0, 0.0]).material("ceiling"),
        ]),
    );
    let frame = common::render_scene(&scene, W, H, &settings());
    let critical = (1.0f32 / 1.5).asin().to_degrees();
    let (mut inside, mut outside) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            let (_, d) = common::pixel_ray(&scene.cameras[0], W, H, x, y);
            // Only rays that reach the top face (not a side face first).
            if d.y <= 0.0 || d.x.abs() > d.y || d.z.abs() > d.y {
                continue;
            }
            let angle = d.y.clamp(-1.0, 1.0).acos().to_degrees();
            let l = frame.radiance(x, y)[0];
            if angle < critical - 2.0 {
                inside += 1;
                assert!(l > 0.3, "pixel ({x},{y}) at {angle:.1}° inside the window is dark: {l}");
            } else if angle > critical + 1.0 && angle < critical + 3.0 {
                // Just past the critical angle the reflected ray is still
                // trapped (it meets every face beyond the critical angle);
                // without TIR it would refract out and see the ceiling.
                outside += 1;
                assert!(l < 0.05, "pixel ({x},{y}) at {angle:.1}° should be totally reflected: {l}");
            }
        }
    }
    assert!(inside > 200 && outside > 50, "window {inside} / TIR {outside} pixels");
}
