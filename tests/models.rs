//! Real models from ../shared/assets: finite, non-black output compared with
//! committed references, and alpha-mask cut-outs.
//!
//! Tolerance: PSNR >= 35 dB against `tests/golden/*.png` (rendered on Mesa
//! lavapipe). That allows driver rounding and filtering differences but not a
//! missing texture, a wrong light or a changed BRDF (each costs well over
//! 10 dB on these views).
mod common;

use hybrid_rt::render::{FrameOutput, RenderSettings};
use hybrid_rt::scene::{AlphaMode, Scene};

const MIN_PSNR: f64 = 35.0;

fn render(scene: &Scene, w: u32, h: u32) -> FrameOutput {
    common::render_scene(scene, w, h, &RenderSettings::default())
}

fn assert_lit(frame: &FrameOutput, min_mean: f64) {
    assert!(frame.all_finite(), "NaN/Inf in the frame");
    let mean =
        frame.ldr.chunks_exact(4).map(|p| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0).sum::<f64>()
            / (frame.width * frame.height) as f64;
    assert!(mean > min_mean, "frame too dark: mean {mean:.1}/255");
}

#[test]
fn damaged_helmet_matches_reference() {
    let scene = Scene::load(&common::shared_asset("gltf/DamagedHelmet/glTF/DamagedHelmet.gltf")).unwrap();
    let frame = render(&scene, 160, 90);
    assert_lit(&frame, 5.0);
    common::check_golden(&frame, "damaged_helmet_160x90", MIN_PSNR);
}

#[test]
fn sponza_matches_reference() {
    let scene = Scene::load(&common::shared_asset("scenes/SponzaCapsaicin/Sponza.gltf")).unwrap();
    assert!(scene.triangle_count() > 100_000);
    let frame = render(&scene, 320, 180);
    assert_lit(&frame, 5.0);
    common::check_golden(&frame, "sponza_320x180", MIN_PSNR);
}

#[test]
fn alpha_mask_cuts_out_geometry() {
    let path = common::shared_asset("gltf/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf");
    let scene = Scene::load(&path).unwrap();
    assert!(scene.materials.iter().any(|m| m.alpha_mode == AlphaMode::Mask));
    let masked = render(&scene, 240, 135);
    assert_lit(&masked, 5.0);
    common::check_golden(&masked, "alpha_blend_mode_test_240x135", MIN_PSNR);

    // The same scene with masking switched off must cover clearly more pixels.
    let mut opaque = scene.clone();
    for m in &mut opaque.materials {
        if m.alpha_mode == AlphaMode::Mask {
            m.alpha_mode = AlphaMode::Opaque;
        }
    }
    let solid = render(&opaque, 240, 135);
    let (_, differing) = hybrid_rt::metrics::diff_stats(&masked.ldr, &solid.ldr, 4, 8);
    assert!(differing > 0.01, "alpha mask changed only {:.3}% of pixels", differing * 100.0);
}

/// The documents' test scene: Sponza with reflective and refractive spheres,
/// rendered hybrid (G-buffer + ray-traced shadows, reflections, refractions).
#[test]
fn sponza_with_spheres_matches_reference() {
    let scene = Scene::load(&common::repo_path("assets/sponza_spheres.toml")).unwrap();
    let frame = render(&scene, 320, 180);
    assert_lit(&frame, 5.0);
    common::check_golden(&frame, "sponza_spheres_hybrid_320x180", MIN_PSNR);
}
