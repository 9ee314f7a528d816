//! Shared test helpers: a validated Vulkan context, paths to ../shared assets,
//! golden-image comparison.
#![allow(dead_code)]

pub mod scenes;

use std::path::PathBuf;

use hybrid_rt::app::GpuOptions;
use hybrid_rt::render::FrameOutput;
use hybrid_rt::vk::Context;

/// A context with the Khronos validation layer on (tests always validate).
pub fn validated_context() -> Context {
    let _ = env_logger::builder().is_test(true).try_init();
    GpuOptions { validation: true, ..Default::default() }
        .context()
        .expect("create a validated Vulkan context")
}

/// Panics when the validation layer reported any error on `ctx`.
pub fn assert_validation_clean(ctx: &Context) {
    let c = ctx.validation_counters();
    assert_eq!(c.errors(), 0, "validation layer reported {} error(s) (see log)", c.errors());
}

/// A file under ../shared/assets; a missing asset fails loudly, never skips.
pub fn shared_asset(rel: &str) -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/assets").join(rel);
    assert!(p.exists(), "test asset missing: {} (CI keeps ../shared beside the checkout)", p.display());
    p
}

pub fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub fn out_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("renders");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Compares a frame with `tests/golden/<name>.png` by PSNR (dB). With
/// UPDATE_GOLDEN=1 the reference is (re)written instead. The rendered frame
/// is always saved next to the test target for inspection.
pub fn check_golden(frame: &FrameOutput, name: &str, min_psnr_db: f64) -> f64 {
    let actual = frame.rgb8();
    actual.save(out_dir().join(format!("{name}.png"))).unwrap();
    let golden = repo_path(&format!("tests/golden/{name}.png"));
    if std::env::var("UPDATE_GOLDEN").is_ok_and(|v| v == "1") {
        actual.save(&golden).unwrap();
        return f64::INFINITY;
    }
    let expected = image::open(&golden)
        .unwrap_or_else(|e| panic!("reference {} missing ({e}); run with UPDATE_GOLDEN=1", golden.display()))
        .into_rgb8();
    assert_eq!(expected.dimensions(), actual.dimensions(), "golden {name}: size differs");
    let psnr = hybrid_rt::metrics::psnr_rgb8(expected.as_raw(), actual.as_raw(), 3, None);
    eprintln!("golden {name}: PSNR {psnr:.2} dB (threshold {min_psnr_db} dB)");
    assert!(psnr >= min_psnr_db, "golden {name}: PSNR {psnr:.2} dB below {min_psnr_db} dB");
    psnr
}

/// Writes `toml` to a fresh temp file and loads it as a scene.
pub fn scene_from_toml(name: &str, toml: &str) -> hybrid_rt::scene::Scene {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scenes");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.toml"));
    // Tests running in parallel may write the same scene: write a private
    // file and rename it into place, so no reader sees a half-written one.
    let tmp = dir.join(format!("{name}.toml.{:?}.tmp", std::thread::current().id()));
    std::fs::write(&tmp, toml).unwrap();
    std::fs::rename(&tmp, &path).unwrap();
    hybrid_rt::scene::Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e:#}"))
}

/// Renders `scene` from its first camera with a validated context and checks
/// the frame is finite and validation stayed clean.
pub fn render_scene(
    scene: &hybrid_rt::scene::Scene,
    w: u32,
    h: u32,
    settings: &hybrid_rt::render::RenderSettings,
) -> FrameOutput {
    let ctx = validated_context();
    let mut r =
        hybrid_rt::render::Renderer::new(&ctx, scene, ash::vk::Extent2D { width: w, height: h }).unwrap();
    let out = r.render(&ctx, scene, &scene.cameras[0], settings).unwrap();
    r.destroy(&ctx);
    assert_validation_clean(&ctx);
    assert!(out.all_finite(), "NaN or Inf reached the frame");
    out
}

/// World-space direction of the camera ray through the centre of pixel
/// (x, y), with the renderer's camera model.
pub fn pixel_ray(cam: &hybrid_rt::scene::Camera, w: u32, h: u32, x: u32, y: u32) -> (glam::Vec3, glam::Vec3) {
    let proj = cam.projection(w as f32 / h as f32);
    let ndc_x = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
    let ndc_y = (y as f32 + 0.5) / h as f32 * 2.0 - 1.0;
    let dv = glam::Vec3::new(ndc_x / proj.x_axis.x, ndc_y / proj.y_axis.y, -1.0);
    let rot = glam::Mat3::from_mat4(cam.view()).transpose();
    (cam.position(), (rot * dv).normalize())
}
