//! Shared test helpers: a validated Vulkan context, paths to ../shared assets,
//! golden-image comparison.
#![allow(dead_code)]

use std::path::PathBuf;

use hybrid_rt::app::GpuOptions;
use hybrid_rt::render::FrameOutput;
use hybrid_rt::vk::Context;

/// A context with the Khronos validation layer on (tests always validate).
pub fn validated_context() -> Context {
    let _ = env_logger::builder().is_test(true).try_init();
    GpuOptions { validation: true, ..Default::default() }.context().expect("create a validated Vulkan context")
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
