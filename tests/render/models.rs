//! Real models from ../shared/assets: finite, non-black output compared with
//! committed references, and alpha-mask cut-outs.
//!
//! Tolerance: per pixel against `tests/golden/*.png` (rendered on Mesa
//! lavapipe), see `common::check_golden`: re-renders are bit-identical here,
//! and one object's material changed must fail (tested below).
use crate::common;

use hybrid_rt::render::shading::AaMode;
use hybrid_rt::render::{FrameOutput, RenderSettings};
use hybrid_rt::scene::{AlphaMode, Scene};

fn render(scene: &Scene, w: u32, h: u32) -> FrameOutput {
    // The goldens pin the shading before anti-aliasing (tests/render/antialias.rs
    // tests the filters).
    common::render_scene(scene, w, h, &RenderSettings { aa: AaMode::None, ..Default::default() })
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
    common::check_golden(&frame, "damaged_helmet_160x90");
}

/// The golden tolerance catches a one-object change: the helmet (about 9% of
/// its frame) with its base colour factor 20% darker. PSNR stays above the
/// old 35 dB bound for it (printed), so that bound let it pass.
#[test]
fn golden_check_fails_when_one_material_changes() {
    let mut scene = Scene::load(&common::shared_asset("gltf/DamagedHelmet/glTF/DamagedHelmet.gltf")).unwrap();
    assert_eq!(scene.materials.len(), 1, "DamagedHelmet has one material");
    for c in &mut scene.materials[0].base_color[..3] {
        *c *= 0.8;
    }
    let frame = render(&scene, 160, 90);
    let d = common::golden_diff(&frame, "damaged_helmet_160x90");
    eprintln!(
        "helmet base colour x0.8: {:.3}% pixels differ by > 2/255, max {}/255, PSNR {:.2} dB",
        d.share * 100.0,
        d.max,
        d.psnr_db
    );
    assert!(d.verdict().is_err(), "a changed material passed the golden check: {d:?}");
}

#[test]
fn sponza_matches_reference() {
    let scene = Scene::load(&common::shared_asset("scenes/SponzaCapsaicin/Sponza.gltf")).unwrap();
    assert!(scene.triangle_count() > 100_000);
    let frame = render(&scene, 320, 180);
    assert_lit(&frame, 5.0);
    common::check_golden(&frame, "sponza_320x180");
}

#[test]
fn alpha_mask_cuts_out_geometry() {
    let path = common::shared_asset("gltf/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf");
    let scene = Scene::load(&path).unwrap();
    assert!(scene.materials.iter().any(|m| m.alpha_mode == AlphaMode::Mask));
    let masked = render(&scene, 240, 135);
    assert_lit(&masked, 5.0);
    common::check_golden(&masked, "alpha_blend_mode_test_240x135");

    // The same scene with masking switched off must cover clearly more pixels.
    let mut opaque = scene.clone();
    for m in &mut opaque.materials {
        if m.alpha_mode == AlphaMode::Mask {
            m.alpha_mode = AlphaMode::Opaque;
        }
    }
    let solid = render(&opaque, 240, 135);
    let (_, differing) = hybrid_rt::image_diff::diff_stats(&masked.ldr, &solid.ldr, 4, 8);
    assert!(differing > 0.01, "alpha mask changed only {:.3}% of pixels", differing * 100.0);
}

/// The documents' test scene: Sponza with reflective and refractive spheres,
/// rendered hybrid (G-buffer + ray-traced shadows, reflections, refractions).
#[test]
fn sponza_with_spheres_matches_reference() {
    let scene = Scene::load(&common::repo_path("assets/sponza_spheres.toml")).unwrap();
    let frame = render(&scene, 320, 180);
    assert_lit(&frame, 5.0);
    common::check_golden(&frame, "sponza_spheres_hybrid_320x180");
}
