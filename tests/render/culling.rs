//! Culling in the G-buffer pass (render/cull.rs): an instance entirely
//! outside the view frustum is not drawn, and back-face culling of
//! single-sided geometry keeps a mirrored (negative-scale) instance's
//! outside, so the hybrid image matches pure ray tracing (which culls
//! nothing) there too.
use crate::common;

use common::toml::*;

use hybrid_rt::render::shading::{AaMode, Backend, Mode};
use hybrid_rt::render::{DebugView, RenderSettings, Renderer};
use hybrid_rt::scene::Scene;

const W: u32 = 96;
const H: u32 = 54;

fn settings() -> RenderSettings {
    RenderSettings { backend: Backend::Compute, aa: AaMode::None, ..Default::default() }
}

/// A camera, an unshadowed sun and a clay floor, then `objects`.
fn floor_and<const N: usize>(objects: [Block; N]) -> String {
    let header = [
        camera([0.0, 1.0, 5.0], [0.0, 0.0, 0.0]),
        directional([-0.3, -1.0, -0.5], 3.0).no_shadows(),
        clay(),
        plane("floor", 10.0).at([0.0, -1.0, 0.0]).material("clay"),
    ];
    scene_toml(header.into_iter().chain(objects))
}

/// Renders one hybrid frame; returns the draws recorded and culled.
fn raster_draws(scene: &Scene) -> (usize, u32) {
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let out = r.render(&ctx, scene, &scene.cameras[0], &settings()).unwrap();
    assert!(out.all_finite());
    let draws = r.raster_draws();
    r.destroy(&ctx);
    common::assert_validation_clean(&ctx);
    draws
}

/// A ball behind the camera and one far off to its side are left out;
/// the ball in view and the floor (which the view crosses) are drawn.
#[test]
fn an_instance_outside_the_frustum_is_not_drawn() {
    let toml = floor_and([
        primitive("in view", "sphere").material("clay"),
        primitive("behind the camera", "sphere").at([0.0, 1.0, 9.0]).material("clay"),
        primitive("far to the left", "sphere").at([-40.0, 0.0, 0.0]).material("clay"),
    ]);
    let scene = common::scene_from_toml("cull_outside", &toml);
    assert_eq!(scene.instances.len(), 4);
    assert_eq!(raster_draws(&scene), (2, 2), "(recorded, culled): floor and the ball in view");
}

/// Mirrored boxes (one axis negated, and all three) with single-sided
/// material: the hybrid frame (back-face culled raster) matches pure ray
/// tracing away from silhouettes, as on unmirrored geometry
/// (tests/render/raytracing.rs: PSNR >= 40 dB). Drawn with the unflipped winding,
/// the raster would cull the boxes' outsides and show their insides.
#[test]
fn a_mirrored_single_sided_object_still_renders() {
    let toml = floor_and([
        primitive("mirrored x", "cube")
            .at([-1.2, 0.0, 0.0])
            .rot([0.0, 30.0, 0.0])
            .scale([-1.0, 1.0, 1.0])
            .material("clay"),
        primitive("mirrored xyz", "cube")
            .at([1.2, 0.0, 0.0])
            .rot([20.0, -30.0, 0.0])
            .scale([-0.8, -0.8, -0.8])
            .material("clay"),
    ]);
    let scene = common::scene_from_toml("cull_mirrored", &toml);
    assert!(scene.materials.iter().all(|m| !m.double_sided), "single-sided materials");
    let hybrid = common::render_scene(&scene, W, H, &settings());
    let rt = common::render_scene(&scene, W, H, &RenderSettings { mode: Mode::Rt, ..settings() });
    let ids =
        common::render_scene(&scene, W, H, &RenderSettings { debug_view: DebugView::Object, ..settings() });
    // Away from object silhouettes (where hybrid and RT may differ).
    let id = |x: i32, y: i32| {
        let i = ((y.clamp(0, H as i32 - 1) as u32 * W + x.clamp(0, W as i32 - 1) as u32) * 4) as usize;
        [ids.ldr[i], ids.ldr[i + 1], ids.ldr[i + 2]]
    };
    let mut mask = Vec::new();
    for y in 0..H as i32 {
        for x in 0..W as i32 {
            mask.push((-1..=1).all(|dy| (-1..=1).all(|dx| id(x + dx, y + dy) == id(x, y))));
        }
    }
    let psnr = hybrid_rt::image_diff::psnr_rgb8(&hybrid.ldr, &rt.ldr, 4, Some(&mask));
    eprintln!("mirrored boxes, hybrid vs pure RT: PSNR {psnr:.1} dB over non-edge pixels");
    assert!(psnr >= 40.0, "hybrid and pure RT disagree on mirrored boxes: PSNR {psnr:.1} dB");
}
