//! Emissive surfaces as lights in the hybrid frame (render/passes/ao.rs: light samples on the emissive
//! triangles, MIS-weighted against the traced ambient's cosine rays that hit them), against closed forms
//! and the path tracer.
//!
//! - A small square lamp over a Lambert floor: each floor point reads albedo x L x the lamp's form
//!   factor. The frame's mean within 3 % of the closed form's and each 8x8 block within 10 % on every
//!   backend, with and without the indirect bounce (emitters are direct light). The lamp covers ~7 % of
//!   the cosine lobe below it, so the cosine rays alone (4 a pixel, 64 in a filter window) find it a
//!   few times a window: a block 47 % off, measured. The light samples are what holds the bound.
//! - The same lamp over a rough metal floor (no diffuse lobe, too rough for glossy rays): its highlight
//!   comes from the light samples alone; the frame's mean within 5 % of the path tracer's.
use crate::common;

use common::toml::*;

use hybrid_rt::render::shading::{Backend, Mode};
use hybrid_rt::render::{PathSettings, RenderSettings};

const SIZE: u32 = 64;
/// The lamp's height, half side and radiance.
const H: f32 = 1.0;
const A: f32 = 0.15;
const L: f32 = 20.0;

fn lamp_over(floor: Block, camera_block: Block) -> hybrid_rt::scene::Scene {
    let toml = scene_toml([
        black_sky(),
        camera_block,
        floor,
        emitter("lamp", [L, L, L]),
        plane("floor", 40.0).material("floor"),
        plane("lamp", 2.0 * A).at([0.0, H, 0.0]).rot([180.0, 0.0, 0.0]).material("lamp"),
    ]);
    common::scene_from_toml(&format!("emitters_{:x}", toml.len()), &toml)
}

#[test]
fn a_small_lamp_lights_the_floor_by_its_form_factor() {
    let albedo = 0.5f32;
    let scene = lamp_over(
        lambert("floor", [albedo; 3]).ior(1.0),
        camera([0.0, 0.9, 0.0], [0.0, 0.0, 0.0]).up([0.0, 0.0, -1.0]).yfov(60),
    );
    assert!(scene.lights.is_empty(), "a scene that emits gets no default sun");
    let cam = &scene.cameras[0];
    let a = A as f64;
    let want = |x: u32, y: u32| {
        let (px, pz) = common::floor_point(cam, SIZE, SIZE, x, y);
        albedo as f64 * L as f64 * common::rectangle_form_factor(H as f64, -a - px, a - px, -a - pz, a - pz)
    };
    let mut b = common::Bench::new(&scene, SIZE, SIZE);
    for backend in common::BACKENDS {
        for bounce in [true, false] {
            let settings = RenderSettings { backend, ambient_bounce: bounce, ..Default::default() };
            let f = b.frame(&scene, cam, &settings);
            let green = |x: u32, y: u32| f.hdr[((y * SIZE + x) * 4 + 1) as usize] as f64;
            let (mut got, mut expected, mut worst_block) = (0.0, 0.0, 0.0f64);
            for by in 0..SIZE / 8 {
                for bx in 0..SIZE / 8 {
                    let (mut g, mut w) = (0.0, 0.0);
                    for y in by * 8..by * 8 + 8 {
                        for x in bx * 8..bx * 8 + 8 {
                            g += green(x, y);
                            w += want(x, y);
                        }
                    }
                    worst_block = worst_block.max((g / w - 1.0).abs());
                    got += g;
                    expected += w;
                }
            }
            println!(
                "{backend:?}, bounce {bounce}: floor under a lamp {got:.2} against the form factor's {expected:.2} \
                 ({:+.2} %), worst 8x8 block {:.1} %",
                100.0 * (got / expected - 1.0),
                100.0 * worst_block
            );
            assert!((got / expected - 1.0).abs() < 0.03, "{backend:?}: floor {got} against {expected}");
            assert!(worst_block < 0.10, "{backend:?}: an 8x8 block is {:.1} % off", 100.0 * worst_block);
        }
    }
    b.finish();
}

#[test]
fn a_rough_metal_reflects_a_lamp_as_the_path_tracer_does() {
    let scene = lamp_over(
        material("floor").base([0.9, 0.9, 0.9]).metallic(1.0).roughness(0.8),
        camera([0.0, 0.7, 1.0], [0.0, 0.0, -0.2]).yfov(50),
    );
    let cam = &scene.cameras[0];
    let (w, h) = (48, 32);
    let mut b = common::Bench::new(&scene, w, h);
    let hybrid = b.frame(&scene, cam, &RenderSettings::default());
    b.finish();
    let path = RenderSettings {
        mode: Mode::Path,
        path: PathSettings { samples: 256, ..Default::default() },
        backend: Backend::Compute,
        ..Default::default()
    };
    let ctx = common::validated_context();
    let mut r =
        hybrid_rt::render::Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: w, height: h }).unwrap();
    let truth = hybrid_rt::render::reference::render_converged(&mut r, &ctx, &scene, cam, &path).unwrap();
    r.destroy(&ctx);
    drop(ctx);
    let mean = |f: &hybrid_rt::render::FrameOutput| {
        f.hdr.chunks_exact(4).map(|p| p[1] as f64).sum::<f64>() / (w * h) as f64
    };
    let (got, want) = (mean(&hybrid), mean(&truth));
    println!(
        "rough metal under a lamp: hybrid {got:.4}, path tracer {want:.4} ({:+.2} %)",
        100.0 * (got / want - 1.0)
    );
    assert!(want > 0.01, "the lamp lights the floor in the truth ({want})");
    assert!((got / want - 1.0).abs() < 0.05, "rough metal floor {got} against the path tracer's {want}");
}

/// The `emitter specular` targets (and the passes' `_emitters` variants) exist only where the scene
/// emits: the same room with the lamp switched off has neither, with the traced ambient still running.
#[test]
fn emitter_targets_exist_only_where_the_scene_emits() {
    let camera_block = camera([0.0, 0.9, 0.0], [0.0, 0.0, 0.0]).up([0.0, 0.0, -1.0]).yfov(60);
    for lit in [true, false] {
        let toml = scene_toml([
            environment([0.2, 0.2, 0.2]),
            camera_block.clone(),
            lambert("floor", [0.5; 3]),
            emitter("lamp", if lit { [L; 3] } else { [0.0; 3] }),
            plane("floor", 40.0).material("floor"),
            plane("lamp", 2.0 * A).at([0.0, H, 0.0]).rot([180.0, 0.0, 0.0]).material("lamp"),
        ]);
        let scene = common::scene_from_toml(&format!("emitter_targets_{lit}"), &toml);
        let mut b = common::Bench::new(&scene, 16, 16);
        b.frame(&scene, &scene.cameras[0], &RenderSettings::default());
        let names: Vec<&str> = b.renderer.targets().describe().into_iter().map(|(n, _)| n).collect();
        b.finish();
        assert!(names.contains(&"ambient visibility"), "the traced ambient runs: {names:?}");
        for target in ["emitter specular sample", "emitter specular"] {
            assert_eq!(names.contains(&target), lit, "lamp on: {lit}, targets {names:?}");
        }
    }
}
