//! Shared test helpers: a validated Vulkan context, paths to ../shared assets,
//! golden-image comparison.
#![allow(dead_code)]

pub mod probe;
pub mod scenes;
pub mod toml;

use std::path::PathBuf;
use std::sync::Arc;

use hybrid_rt::app::GpuOptions;
use hybrid_rt::render::FrameOutput;
use hybrid_rt::vk::{Context, ValidationCounters};

/// A validated context that, when dropped, destroys the device and instance
/// first and only then checks the validation counters: leaked objects are
/// reported by vkDestroyDevice / vkDestroyInstance, after any check a test
/// could make while the context lives.
pub struct ValidatedContext {
    ctx: Option<Context>,
    counters: Arc<ValidationCounters>,
}

impl std::ops::Deref for ValidatedContext {
    type Target = Context;
    fn deref(&self) -> &Context {
        self.ctx.as_ref().expect("context alive until drop")
    }
}

impl ValidatedContext {
    /// Tears the context down now: an error when validation reported any,
    /// teardown (leaked objects) included.
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.ctx.take().expect("context alive until finish").finish()
    }
}

impl Drop for ValidatedContext {
    fn drop(&mut self) {
        // Already checked by `finish`.
        let Some(ctx) = self.ctx.take() else { return };
        drop(ctx);
        // A second panic while unwinding would abort and hide the first.
        if !std::thread::panicking() {
            let e = self.counters.errors();
            assert_eq!(e, 0, "validation layer reported {e} error(s), teardown included (see log)");
        }
    }
}

/// Wraps a context created with validation on (see [`ValidatedContext`]).
pub fn validated(ctx: Context) -> ValidatedContext {
    assert!(ctx.instance.validation, "validated() needs a context created with validation on");
    ValidatedContext { counters: ctx.validation_counters(), ctx: Some(ctx) }
}

/// A context with the Khronos validation layer on (tests always validate);
/// its validation errors, teardown included, fail the test when it drops.
pub fn validated_context() -> ValidatedContext {
    let _ = env_logger::builder().is_test(true).try_init();
    validated(
        GpuOptions { validation: true, ..Default::default() }
            .context()
            .expect("create a validated Vulkan context"),
    )
}

/// Panics when the validation layer reported any error on `ctx` so far
/// (a [`ValidatedContext`] checks again after teardown).
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

/// Golden tolerance. A pixel "differs" when any 8-bit channel is off by more
/// than GOLDEN_NOISE; at most GOLDEN_MAX_SHARE of the pixels may differ, and
/// none by more than GOLDEN_MAX_ERROR. Measured on lavapipe: every golden
/// re-renders with 0 differing pixels (max error 0), while one material
/// changed on one object differs on several % of the frame (see
/// tests/render/models.rs) — a PSNR bound of 35 dB let that pass.
pub const GOLDEN_NOISE: u8 = 2;
pub const GOLDEN_MAX_SHARE: f64 = 0.001;
pub const GOLDEN_MAX_ERROR: u8 = 16;

/// How a frame differs from its reference.
#[derive(Clone, Copy, Debug)]
pub struct GoldenDiff {
    /// Largest channel difference (0..=255).
    pub max: u8,
    /// Share of pixels whose largest channel difference exceeds GOLDEN_NOISE.
    pub share: f64,
    pub psnr_db: f64,
}

impl GoldenDiff {
    /// Err (with the numbers) when the difference exceeds the tolerance.
    pub fn verdict(&self) -> Result<(), String> {
        if self.share > GOLDEN_MAX_SHARE || self.max > GOLDEN_MAX_ERROR {
            return Err(format!(
                "{:.4}% of pixels differ by > {GOLDEN_NOISE}/255 (bound {:.4}%), max error {}/255 \
                 (bound {GOLDEN_MAX_ERROR}), PSNR {:.2} dB",
                self.share * 100.0,
                GOLDEN_MAX_SHARE * 100.0,
                self.max,
                self.psnr_db
            ));
        }
        Ok(())
    }
}

/// Compares a frame with `tests/golden/<name>.png` without asserting.
pub fn golden_diff(frame: &FrameOutput, name: &str) -> GoldenDiff {
    let actual = frame.rgb8();
    let golden = repo_path(&format!("tests/golden/{name}.png"));
    let expected = image::open(&golden)
        .unwrap_or_else(|e| panic!("reference {} missing ({e}); run with UPDATE_GOLDEN=1", golden.display()))
        .into_rgb8();
    assert_eq!(expected.dimensions(), actual.dimensions(), "golden {name}: size differs");
    let (max, share) = hybrid_rt::image_diff::diff_stats(expected.as_raw(), actual.as_raw(), 3, GOLDEN_NOISE);
    let psnr_db = hybrid_rt::image_diff::psnr_rgb8(expected.as_raw(), actual.as_raw(), 3, None);
    GoldenDiff { max, share, psnr_db }
}

/// Checks a frame against `tests/golden/<name>.png` (tolerance above). With
/// UPDATE_GOLDEN=1 the reference is (re)written and the test fails, so a
/// run that rewrites goldens never passes (review the new image, then run
/// again without it); never under CI (`.ci/run` sets CI=true itself). The
/// rendered frame is always saved next to the test target for inspection.
pub fn check_golden(frame: &FrameOutput, name: &str) -> GoldenDiff {
    frame.rgb8().save(out_dir().join(format!("{name}.png"))).unwrap();
    if std::env::var("UPDATE_GOLDEN").is_ok_and(|v| v == "1") {
        assert!(
            !std::env::var("CI").is_ok_and(|v| v == "true"),
            "UPDATE_GOLDEN=1 with CI=true: references are never rewritten in CI; unset UPDATE_GOLDEN"
        );
        let path = repo_path(&format!("tests/golden/{name}.png"));
        frame.rgb8().save(&path).unwrap();
        panic!("UPDATE_GOLDEN=1: rewrote {}; review it and run again without UPDATE_GOLDEN", path.display());
    }
    let d = golden_diff(frame, name);
    eprintln!(
        "golden {name}: {:.4}% of pixels differ by > {GOLDEN_NOISE}/255, max error {}/255, PSNR {:.2} dB",
        d.share * 100.0,
        d.max,
        d.psnr_db
    );
    if let Err(e) = d.verdict() {
        panic!("golden {name}: {e}");
    }
    d
}

/// Writes a `w` x `h` Radiance .hdr named `name` (in the tests' temp
/// directory) whose texel (x, y) is `f(x, y)`; returns its path.
pub fn write_hdr(name: &str, w: u32, h: u32, mut f: impl FnMut(u32, u32) -> [f32; 3]) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.hdr"));
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            pixels.push(image::Rgb(f(x, y)));
        }
    }
    let file = std::fs::File::create(&path).unwrap();
    image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(file))
        .encode(&pixels, w as usize, h as usize)
        .unwrap();
    path
}

/// Writes `toml` to a fresh temp file and loads it as a scene.
pub fn scene_from_toml(name: &str, toml: &str) -> hybrid_rt::scene::Scene {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scenes");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.toml"));
    // Tests running in parallel (threads, or test processes sharing the
    // target dir) may write the same scene: write a private file and rename
    // it into place, so no reader sees a half-written one.
    let tmp = dir.join(format!("{name}.toml.{}.{:?}.tmp", std::process::id(), std::thread::current().id()));
    std::fs::write(&tmp, toml).unwrap();
    std::fs::rename(&tmp, &path).unwrap();
    hybrid_rt::scene::Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e:#}"))
}

/// The ray backends lavapipe offers: every cross-backend test runs all three.
pub const BACKENDS: [hybrid_rt::render::shading::Backend; 3] = [
    hybrid_rt::render::shading::Backend::Query,
    hybrid_rt::render::shading::Backend::Pipeline,
    hybrid_rt::render::shading::Backend::Compute,
];

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
    drop(ctx); // validation errors, teardown included, fail here
    assert!(out.all_finite(), "NaN or Inf reached the frame");
    out
}

/// Form factor from a point to the rectangle [x1, x2] x [z1, z2] (offsets from the point) of a parallel
/// plane at height h above it: the share of its cosine-weighted hemisphere the rectangle covers, by
/// inclusion-exclusion over the corner rectangles (each the closed form of a rectangle with a corner
/// above the point).
pub fn rectangle_form_factor(h: f64, x1: f64, x2: f64, z1: f64, z2: f64) -> f64 {
    let corner = |u: f64, v: f64| {
        let (x, y) = ((u / h).abs(), (v / h).abs());
        let f = (x / (1.0 + x * x).sqrt() * (y / (1.0 + x * x).sqrt()).atan()
            + y / (1.0 + y * y).sqrt() * (x / (1.0 + y * y).sqrt()).atan())
            / (2.0 * std::f64::consts::PI);
        f * u.signum() * v.signum()
    };
    corner(x2, z2) - corner(x1, z2) - corner(x2, z1) + corner(x1, z1)
}

/// World-space direction of the camera ray through the centre of pixel
/// (x, y), with the renderer's camera model.
pub fn pixel_ray(cam: &hybrid_rt::scene::Camera, w: u32, h: u32, x: u32, y: u32) -> (glam::Vec3, glam::Vec3) {
    let proj = cam.projection(w as f32 / h as f32);
    let ndc_x = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
    let ndc_y = (y as f32 + 0.5) / h as f32 * 2.0 - 1.0;
    let dv = glam::Vec3::new(ndc_x / proj.x_axis.x, ndc_y / proj.y_axis.y, -1.0);
    let rot = glam::Mat3::from_mat4(cam.view().as_mat4()).transpose();
    (cam.position(), (rot * dv).normalize())
}

/// The point of the floor (y = 0) that pixel (x, y) of a w x h frame sees, as (x, z).
pub fn floor_point(cam: &hybrid_rt::scene::Camera, w: u32, h: u32, x: u32, y: u32) -> (f64, f64) {
    let (o, d) = pixel_ray(cam, w, h, x, y);
    let t = -o.y / d.y;
    ((o.x + d.x * t) as f64, (o.z + d.z * t) as f64)
}

/// A context with validation and synchronization validation on; like
/// [`validated_context`], its errors, teardown included, fail the test.
pub fn sync_validated_context() -> ValidatedContext {
    let _ = env_logger::builder().is_test(true).try_init();
    validated(
        GpuOptions { validation: true, sync_validation: true, ..Default::default() }
            .context()
            .expect("create a Vulkan context with synchronization validation"),
    )
}

/// Standard base64 with padding, for glTF `data:` URIs written by tests.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let n = chunk.iter().enumerate().fold(0u32, |n, (i, &b)| n | (b as u32) << (16 - 8 * i));
        for i in 0..4 {
            out.push(if i <= chunk.len() {
                ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// Splits a CSV line, honouring RFC 4180 quotes.
pub fn split_csv(line: &str) -> Vec<String> {
    let (mut fields, mut cur, mut quoted, mut chars) =
        (Vec::new(), String::new(), false, line.chars().peekable());
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => fields.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    fields.push(cur);
    fields
}

/// The binary's `render` at 16x9 with the validation layer on: for the
/// command-line tests of flags (append the flags under test).
pub fn tiny_render_cmd() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    c.env("HYBRID_RT_VALIDATION", "1").args(["render", "--width", "16", "--height", "9"]);
    c
}

/// A validated context and a renderer of one size: frames that must be
/// finite, and a teardown whose validation errors (leaks included) fail.
pub struct Bench {
    pub ctx: ValidatedContext,
    pub renderer: hybrid_rt::render::Renderer,
}

impl Bench {
    pub fn new(scene: &hybrid_rt::scene::Scene, w: u32, h: u32) -> Bench {
        let ctx = validated_context();
        let extent = ash::vk::Extent2D { width: w, height: h };
        let renderer = hybrid_rt::render::Renderer::new(&ctx, scene, extent).unwrap();
        Bench { ctx, renderer }
    }

    /// One frame (with an accumulating pass: one more frame of it).
    pub fn frame(
        &mut self,
        scene: &hybrid_rt::scene::Scene,
        camera: &hybrid_rt::scene::Camera,
        settings: &hybrid_rt::render::RenderSettings,
    ) -> FrameOutput {
        let out = self.renderer.render(&self.ctx, scene, camera, settings).unwrap();
        assert!(out.all_finite(), "NaN or Inf reached the frame");
        out
    }

    /// The scene's first camera on every backend (BACKENDS) with `base`'s other settings, named
    /// "hybrid <backend>" (or whatever `base.mode` is, e.g. "Rt <backend>").
    pub fn every_backend(
        &mut self,
        scene: &hybrid_rt::scene::Scene,
        base: &hybrid_rt::render::RenderSettings,
    ) -> Vec<(String, FrameOutput)> {
        use hybrid_rt::render::shading::Mode;
        let mode = if base.mode == Mode::Hybrid { "hybrid".to_string() } else { format!("{:?}", base.mode) };
        BACKENDS
            .iter()
            .map(|&backend| {
                let settings = hybrid_rt::render::RenderSettings { backend, ..*base };
                (format!("{mode} {backend:?}"), self.frame(scene, &scene.cameras[0], &settings))
            })
            .collect()
    }

    pub fn finish(mut self) {
        self.renderer.destroy(&self.ctx);
        drop(self.ctx); // validation errors, teardown included, fail here
    }
}

/// Over the pixels whose camera ray looks down (at a ground plane below the camera; rays within 0.05 of
/// level left out): the mean green channel of `f`, the mean of `want` at each ray's cosine to the
/// vertical, and the largest |got - want|.
pub fn floor_error(
    f: &FrameOutput,
    cam: &hybrid_rt::scene::Camera,
    want: impl Fn(f64) -> f64,
) -> (f64, f64, f64) {
    let (w, h) = (f.width, f.height);
    let (mut worst, mut n, mut sum_got, mut sum_want) = (0.0f64, 0, 0.0, 0.0);
    for y in 0..h {
        for x in 0..w {
            let (_, d) = pixel_ray(cam, w, h, x, y);
            if d.y > -0.05 {
                continue;
            }
            let wanted = want((-d.y as f64).min(1.0));
            let got = f.hdr[((y * w + x) * 4 + 1) as usize] as f64;
            worst = worst.max((got - wanted).abs());
            sum_got += got;
            sum_want += wanted;
            n += 1;
        }
    }
    assert!(n > (w * h / 3) as usize, "the floor fills the lower half");
    (sum_got / n as f64, sum_want / n as f64, worst)
}

/// Pixels of the ground (y = 0) within `radius` of the origin whose camera
/// ray does not pass through a sphere of radius 0.5 (plus a margin for its
/// tessellation) centred 1.0 above the origin, with their points.
pub fn ground_pixels(
    cam: &hybrid_rt::scene::Camera,
    w: u32,
    h: u32,
    radius: f32,
) -> Vec<(usize, glam::Vec3)> {
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (o, d) = pixel_ray(cam, w, h, x, y);
            if d.y >= 0.0 {
                continue;
            }
            let p = o + d * (-o.y / d.y);
            let c = glam::Vec3::new(0.0, 1.0, 0.0);
            let blocked = (o + d * (c - o).dot(d) - c).length() < 0.52;
            if p.length() <= radius && !blocked {
                out.push(((y * w + x) as usize, p));
            }
        }
    }
    out
}
