//! Glossy ray-traced reflections (render/passes/glossy.rs), against the path-traced truth: a glossy metal
//! floor (roughness 0.3) in front of a red emitting wall under a blue constant sky. Where the floor's lobe
//! meets the wall, the truth reflects red; the split sum alone (what surfaces between MIRROR_ROUGHNESS and
//! GLOSSY_ROUGHNESS had before this pass, and still have with reflections off) reflects the sky through
//! the wall. Measured over the floor in front of the wall, per channel, hybrid / truth (256 paths):
//! with the glossy pass within 12 % (measured below); the split sum alone misses by far more (printed).
use crate::common;

use common::toml::*;

use ash::vk::Extent2D;
use glam::Vec3;
use hybrid_rt::render::settings::Effects;
use hybrid_rt::render::shading::{AaMode, Mode};
use hybrid_rt::render::{FrameOutput, PathSettings, RenderSettings, Renderer};

fn scene() -> hybrid_rt::scene::Scene {
    let toml = scene_toml([
        environment([0.25, 0.35, 0.7]),
        camera([0.0, 1.0, 2.5], [0.0, 0.1, -1.0]).yfov(40),
        no_light(),
        material("glossy floor").base([0.9, 0.9, 0.9]).metallic(1.0).roughness(0.3),
        // Black and emitting: its radiance is the same in both renderers (no light it reflects).
        emitter("red", [2.0, 0.2, 0.1]).base([0.0, 0.0, 0.0]).roughness(1.0),
        plane("floor", [6.0, 6.0]).material("glossy floor"),
        cube("wall", 1.0).scale([3.0, 1.5, 0.2]).at([0.0, 0.75, -1.2]).material("red"),
    ]);
    common::scene_from_toml("glossy_floor_red_wall", &toml)
}

/// The path-traced truth, 256 paths a pixel.
fn truth() -> RenderSettings {
    RenderSettings {
        mode: Mode::Path,
        path: PathSettings { samples: 256, ..Default::default() },
        ..Default::default()
    }
}

/// Floor pixels whose point lies between the camera and the wall, close to it (z in [-1.0, -0.3]).
fn floor_in_front_of_the_wall(scene: &hybrid_rt::scene::Scene, w: u32, h: u32) -> Vec<usize> {
    let cam = &scene.cameras[0];
    let mut pixels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (o, d): (Vec3, Vec3) = common::pixel_ray(cam, w, h, x, y);
            if d.y >= 0.0 {
                continue;
            }
            let p = o + d * (-o.y / d.y);
            if (-1.0..=-0.3).contains(&p.z) && p.x.abs() < 1.0 {
                pixels.push((y * w + x) as usize);
            }
        }
    }
    pixels
}

#[test]
fn glossy_reflections_match_the_path_traced_floor() {
    let (w, h) = (96, 54);
    let scene = scene();
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, &scene, Extent2D { width: w, height: h }).unwrap();
    let cam = &scene.cameras[0];
    let hybrid = RenderSettings { aa: AaMode::None, ..Default::default() };
    let split_sum = RenderSettings {
        effects: Effects { reflections: false, ..Effects::default() },
        aa: AaMode::None,
        ..Default::default()
    };
    let truth = truth();
    let mut frames: Vec<FrameOutput> = Vec::new();
    for s in [&hybrid, &split_sum, &truth] {
        let f = hybrid_rt::render::reference::render_converged(&mut r, &ctx, &scene, cam, s).unwrap();
        assert!(f.all_finite(), "NaN or Inf reached the frame");
        frames.push(f);
    }
    r.destroy(&ctx);
    drop(ctx);
    let pixels = floor_in_front_of_the_wall(&scene, w, h);
    assert!(pixels.len() >= 200, "{} floor pixels", pixels.len());
    let sum = |f: &FrameOutput, ch: usize| pixels.iter().map(|i| f.hdr[i * 4 + ch] as f64).sum::<f64>();
    for ch in 0..3 {
        let (glossy, alone) =
            (sum(&frames[0], ch) / sum(&frames[2], ch), sum(&frames[1], ch) / sum(&frames[2], ch));
        println!("channel {ch}: hybrid / path-traced {glossy:.4}, split sum alone {alone:.4}");
        assert!((glossy - 1.0).abs() < 0.12, "channel {ch}: glossy reflections / truth {glossy}");
    }
}

/// Temporal reuse (the viewer's `glossy_temporal`): with the camera still, each frame draws new lobe
/// samples and `glossy temporal` blends them into the reprojected history, so the floor's per-pixel
/// error against the truth falls frame by frame (measured: 0.056 after one frame, 0.027 after 16). A
/// camera that moves away and back keeps nothing stale: after a frame from elsewhere the floor's history
/// is rejected (the view turned far past the lobe's width), not reused.
#[test]
fn glossy_history_lowers_the_noise_of_a_still_view() {
    let (w, h) = (96, 54);
    let scene = scene();
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, &scene, Extent2D { width: w, height: h }).unwrap();
    let cam = &scene.cameras[0];
    let truth = hybrid_rt::render::reference::render_converged(&mut r, &ctx, &scene, cam, &truth()).unwrap();
    let hybrid = RenderSettings { aa: AaMode::None, glossy_temporal: true, ..Default::default() };
    let pixels = floor_in_front_of_the_wall(&scene, w, h);
    // RMS over the floor of the relative difference (red channel, the wall's colour).
    let rms = |f: &FrameOutput| {
        let e: f64 = pixels
            .iter()
            .map(|i| {
                let (a, b) = (f.hdr[i * 4] as f64, truth.hdr[i * 4] as f64);
                ((a - b) / b.max(1e-3)).powi(2)
            })
            .sum::<f64>();
        (e / pixels.len() as f64).sqrt()
    };
    let mut errors = Vec::new();
    for _ in 0..16 {
        let f = r.render(&ctx, &scene, cam, &hybrid).unwrap();
        assert!(f.all_finite(), "NaN or Inf reached the frame");
        errors.push(rms(&f));
    }
    println!("floor RMS relative error by frame: {errors:.4?}");
    assert!(errors[15] < 0.6 * errors[0], "16 frames {} against one {}", errors[15], errors[0]);
    // Elsewhere for a frame, then back: the first frame back starts over.
    let mut away = cam.clone();
    away.world = glam::DMat4::from_translation(glam::DVec3::new(3.0, 0.0, 0.0)) * away.world;
    r.render(&ctx, &scene, &away, &hybrid).unwrap();
    let back = rms(&r.render(&ctx, &scene, cam, &hybrid).unwrap());
    println!("first frame back: {back:.4}");
    assert!(
        back > 0.8 * errors[0],
        "a stale history came back: {back} against a first frame's {}",
        errors[0]
    );
    r.destroy(&ctx);
    drop(ctx);
}
