//! Tone mapping and auto exposure: the compiled tone curves and adaptation
//! (through the shading probe), the GPU luminance reduction against a CPU
//! computation on the same pixels, and black, blinding and NaN/Inf frames
//! on every backend.
use crate::common;

use std::path::PathBuf;

use ash::vk;
use common::probe::{self, Case};
use common::toml::*;
use hybrid_rt::gpu::shared::{
    HIST_BINS, HIST_MAX_LOG2, HIST_MIN_LOG2, LOG_AVERAGE_DELTA, TONEMAP_ACES, TONEMAP_NONE, TONEMAP_REINHARD,
    TONEMAP_REINHARD_WHITE,
};
use hybrid_rt::render::shading::{AaMode, Backend};
use hybrid_rt::render::tone::{AutoExposure, ExposureState, ToneOperator, ToneSettings};
use hybrid_rt::render::{FrameOutput, RenderSettings, Renderer};
use hybrid_rt::scene::Scene;

const OPS: [(u32, &str); 4] = [
    (TONEMAP_REINHARD, "reinhard"),
    (TONEMAP_REINHARD_WHITE, "reinhard-white"),
    (TONEMAP_ACES, "aces"),
    (TONEMAP_NONE, "none"),
];

#[test]
fn tone_curves_map_zero_to_zero_and_never_decrease() {
    // Grey and coloured ramps from 0 to 1e6, log-spaced.
    let levels: Vec<f32> =
        std::iter::once(0.0).chain((0..=200).map(|i| 10f32.powf(-6.0 + 12.0 * i as f32 / 200.0))).collect();
    let tints = [[1.0, 1.0, 1.0], [1.0, 0.4, 0.1], [0.05, 0.2, 1.0]];
    let mut cases = Vec::new();
    for (op, _) in OPS {
        for t in tints {
            for &l in &levels {
                cases.push(Case::tonemap(op, [t[0] * l, t[1] * l, t[2] * l], 4.0));
            }
        }
    }
    let out = probe::run(&cases);
    let n = levels.len();
    for (k, (_, name)) in OPS.iter().enumerate() {
        for (j, t) in tints.iter().enumerate() {
            let ramp = &out[(k * tints.len() + j) * n..][..n];
            assert_eq!(&ramp[0][..3], &[0.0; 3], "{name}: 0 must map to 0");
            for i in 1..n {
                for (c, (&a, &b)) in ramp[i - 1][..3].iter().zip(&ramp[i][..3]).enumerate() {
                    assert!(
                        b.is_finite() && (0.0..=1.0).contains(&b),
                        "{name} tint {t:?}: {b} at {}",
                        levels[i]
                    );
                    assert!(
                        b >= a,
                        "{name} tint {t:?} channel {c}: {a} -> {b} from {} to {}",
                        levels[i - 1],
                        levels[i]
                    );
                }
            }
            // Strictly increasing where the curve is not saturated.
            let l = |i: usize| 0.2126 * ramp[i][0] + 0.7152 * ramp[i][1] + 0.0722 * ramp[i][2];
            let mid = levels.iter().position(|&v| v >= 0.1).unwrap();
            assert!(l(mid + 5) > l(mid), "{name}: flat around 0.1");
        }
    }
    // Closed forms: Reinhard L/(1+L) at L = 1 on grey; the white point maps to 1.
    let g = probe::run(&[
        Case::tonemap(TONEMAP_REINHARD, [1.0; 3], 4.0),
        Case::tonemap(TONEMAP_REINHARD_WHITE, [4.0; 3], 4.0),
        Case::tonemap(TONEMAP_REINHARD_WHITE, [1.0; 3], 4.0),
        Case::tonemap(TONEMAP_NONE, [0.25, 2.0, 0.5], 4.0),
    ]);
    assert!((g[0][0] - 0.5).abs() < 1e-6, "reinhard(1) = {}", g[0][0]);
    assert!((g[1][0] - 1.0).abs() < 1e-6, "reinhard-white(white) = {}", g[1][0]);
    assert!((g[2][0] - 1.0 * (1.0 + 1.0 / 16.0) / 2.0).abs() < 1e-6, "reinhard-white(1) = {}", g[2][0]);
    assert_eq!(&g[3][..3], &[0.25, 1.0, 0.5], "none: exposure + clamp");
}

#[test]
fn adaptation_after_one_second_is_the_same_at_30_and_120_fps() {
    let speeds = [3.0, 1.0];
    // Darkening (target below adapted: the image brightens) and brightening.
    for (from, to) in [(1.0f32, 0.05f32), (0.02, 3.0)] {
        let r = probe::run(&[
            Case::adapt(from, to, 1.0 / 30.0, 30, speeds),
            Case::adapt(from, to, 1.0 / 120.0, 120, speeds),
            Case::adapt(from, to, 1.0 / 30.0, 3, speeds),
            Case::adapt(from, to, 0.0, 1, speeds),
        ]);
        for (i, what) in [(0, "log-average"), (1, "histogram")] {
            let (a30, a120) = (r[0][i], r[1][i]);
            assert!(
                ((a30 - a120) / a120).abs() < 1e-4,
                "{what} {from} -> {to}: {a30} after 1 s at 30 fps, {a120} at 120 fps"
            );
            // Not instantaneous: a tenth of a second in, it is on its way.
            let early = r[2][i];
            assert!(
                (early - from).abs() > 1e-4
                    && (early - to).abs() > 1e-3 * to
                    && (early - from) * (to - from) > 0.0,
                "{what} {from} -> {to}: {early} after 0.1 s"
            );
            assert_eq!(r[3][i], to, "{what}: dt 0 converges at once");
        }
        // The document's formula, closed form: after 1 s the remaining
        // distance is 0.98^60 of the start's.
        let expect = to + (from - to) * 0.98f32.powf(60.0);
        assert!(((r[0][0] - expect) / expect).abs() < 1e-4, "log-average: {} vs {expect}", r[0][0]);
        // Histogram: constant EV speed, 3 EV/s brightening, 1 EV/s darkening.
        let ev = (to / from).log2();
        let moved = ev.clamp(-3.0, 1.0);
        let expect = from * 2f32.powf(moved);
        assert!(((r[0][1] - expect) / expect).abs() < 1e-4, "histogram: {} vs {expect}", r[0][1]);
    }
}

/// A `w` x `h` Radiance .hdr whose texels are log-uniform in [1e-3, 1e4],
/// pseudo-random (fixed seed), grey with some colour.
fn random_hdr(name: &str, w: u32, h: u32) -> PathBuf {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    common::write_hdr(name, w, h, |_, _| {
        let l = 10f32.powf(-3.0 + 7.0 * next());
        [l * (0.5 + next()), l, l * (0.5 + next())]
    })
}

/// A scene that is only its environment `env`.
fn sky(name: &str, env: Block) -> Scene {
    common::scene_from_toml(name, &scene_toml([env, camera([0.0; 3], [0.0, 0.3, -1.0]).yfov(100)]))
}

/// Auto exposure `mode`, no anti-aliasing (the checks read exact pixels).
fn auto(mode: AutoExposure) -> RenderSettings {
    RenderSettings {
        tone: ToneSettings { auto_exposure: mode, ..Default::default() },
        aa: AaMode::None,
        ..Default::default()
    }
}

fn luminance(p: [f32; 3]) -> f64 {
    (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]).max(0.0) as f64
}

fn state(frame: &FrameOutput) -> ExposureState {
    frame.exposure.expect("auto exposure measured the frame")
}

#[test]
fn log_average_and_histogram_match_a_cpu_computation_on_the_same_pixels() {
    let map = random_hdr("tonemap_random", 256, 128);
    let scene = sky("tonemap_random", environment_hdr(map.display()));
    let (w, h) = (203, 117);
    let frame = common::render_scene(&scene, w, h, &auto(AutoExposure::LogAverage));
    let s = state(&frame);
    let lum: Vec<f64> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| luminance(frame.radiance(x, y)))
        .collect();
    let spread = lum.iter().cloned().fold(0.0, f64::max) / lum.iter().cloned().fold(f64::MAX, f64::min);
    assert!(spread > 1e3, "the image is not varied enough to test with (max/min {spread:.1})");
    let mean_log = lum.iter().map(|l| (LOG_AVERAGE_DELTA as f64 + l).ln()).sum::<f64>() / lum.len() as f64;
    let cpu = mean_log.exp();
    assert_eq!(s.finite_pixels, w * h);
    assert!(
        ((s.log_average as f64 - cpu) / cpu).abs() < 1e-4,
        "GPU log-average {} vs CPU {cpu}",
        s.log_average
    );
    let max = lum.iter().cloned().fold(0.0, f64::max);
    assert!(((s.max_luminance as f64 - max) / max).abs() < 1e-6, "max {} vs {max}", s.max_luminance);
    // A still frame converges: exposure = key / log-average.
    assert!(((s.exposure as f64 - 0.18 / cpu) * cpu / 0.18).abs() < 1e-4, "exposure {}", s.exposure);

    // Histogram: the bin-centre mean between the 10th and 90th percentiles.
    let frame = common::render_scene(&scene, w, h, &auto(AutoExposure::Histogram));
    let s = state(&frame);
    let mut bins = vec![0u64; HIST_BINS as usize];
    let range = (HIST_MAX_LOG2 - HIST_MIN_LOG2) as f64;
    for &l in &lum {
        let t = (l.max(1e-30).log2() - HIST_MIN_LOG2 as f64) / range;
        bins[((t * HIST_BINS as f64).clamp(0.0, HIST_BINS as f64 - 1.0)) as usize] += 1;
    }
    let n = lum.len() as f64;
    let (lo, hi) = (0.1 * n, 0.9 * n);
    let (mut below, mut sum, mut weight) = (0.0, 0.0, 0.0);
    for (b, &c) in bins.iter().enumerate() {
        let overlap = ((below + c as f64).min(hi) - below.max(lo)).max(0.0);
        sum += overlap * (HIST_MIN_LOG2 as f64 + (b as f64 + 0.5) * range / HIST_BINS as f64);
        weight += overlap;
        below += c as f64;
    }
    let cpu = (sum / weight).exp2();
    // A pixel right at a bin edge may land on either side in f32: 1e-3.
    assert!(((s.target as f64 - cpu) / cpu).abs() < 1e-3, "histogram target {} vs CPU {cpu}", s.target);
    assert!((s.adapted - s.target).abs() <= 1e-6 * s.target, "a still frame converges");
}

#[test]
fn eye_adaptation_through_the_renderer_is_frame_rate_independent() {
    // Bright sky, then a camera looking at a dark floor: the exposure adapts
    // over one second at 30 and at 120 fps and must land on the same value.
    let scene = common::scene_from_toml(
        "tonemap_adapt",
        &scene_toml([
            environment([2.0, 2.0, 2.0]),
            camera([0.0, 1.0, 0.0], [0.0, 2.0, -1.0]),
            camera([0.0, 1.0, 0.0], [0.0, 0.0, -0.2]),
            lambert("floor", [0.05, 0.05, 0.05]),
            plane("floor", [100.0, 100.0]).material("floor"),
        ]),
    );
    let run = |fps: u32| -> Vec<ExposureState> {
        let ctx = common::validated_context();
        let mut r = Renderer::new(&ctx, &scene, vk::Extent2D { width: 48, height: 27 }).unwrap();
        let settings = auto(AutoExposure::LogAverage);
        let mut states = vec![state(&r.render(&ctx, &scene, &scene.cameras[0], &settings).unwrap())];
        r.choices.adapt_dt = Some(1.0 / fps as f32);
        for _ in 0..fps {
            states.push(state(&r.render(&ctx, &scene, &scene.cameras[1], &settings).unwrap()));
        }
        r.destroy(&ctx);
        states
    };
    let (s30, s120) = (run(30), run(120));
    let (bright, dark) = (s30[0].adapted, s30.last().unwrap().target);
    assert!(bright > 4.0 * dark, "the two views differ too little to test with: {bright} vs {dark}");
    let (a30, a120) = (s30.last().unwrap().adapted, s120.last().unwrap().adapted);
    assert!(((a30 - a120) / a120).abs() < 1e-3, "after 1 s: {a30} at 30 fps, {a120} at 120 fps");
    let expect = dark + (bright - dark) * 0.98f32.powf(60.0);
    assert!(((a30 - expect) / expect).abs() < 1e-3, "after 1 s: {a30}, the formula says {expect}");
    // Gradual: the first step moved only part of the way.
    let first = s30[1].adapted;
    assert!(
        first < bright && first > dark + 0.5 * (bright - dark),
        "first step: {bright} -> {first} (target {dark})"
    );
}

/// One context and one renderer per scene for a backend's frames (64x36).
struct Frames {
    ctx: common::ValidatedContext,
    renderers: Vec<(String, Renderer)>,
}

impl Frames {
    fn new() -> Frames {
        Frames { ctx: common::validated_context(), renderers: Vec::new() }
    }

    /// Renders `scene` (by `name`) from its first camera, injecting
    /// `inject` radiance after `composite` (empty: none).
    fn render(
        &mut self,
        name: &str,
        scene: &Scene,
        settings: &RenderSettings,
        inject: &[([u32; 2], [f32; 3])],
    ) -> FrameOutput {
        let ctx = &self.ctx;
        if !self.renderers.iter().any(|(n, _)| n == name) {
            let r = Renderer::new(ctx, scene, vk::Extent2D { width: 64, height: 36 }).unwrap();
            self.renderers.push((name.to_string(), r));
        }
        let r = &mut self.renderers.iter_mut().find(|(n, _)| n == name).unwrap().1;
        r.inject_radiance(inject).unwrap();
        r.render(ctx, scene, &scene.cameras[0], settings).unwrap()
    }

    /// Destroys the renderers; validation (teardown included) fails here.
    fn finish(mut self) {
        for (_, mut r) in self.renderers.drain(..) {
            r.destroy(&self.ctx);
        }
    }
}

fn ldr(f: &FrameOutput, x: u32, y: u32) -> [u8; 4] {
    let i = ((y * f.width + x) * 4) as usize;
    f.ldr[i..i + 4].try_into().unwrap()
}

/// A mirror sphere under a sky of radiance `sky` and a sun of `sun`: the
/// reflections are traced, so the backend matters.
fn mirror_under(name: &str, sky: f32, sun: f32) -> Scene {
    let toml = scene_toml([
        environment([sky, sky, sky]),
        camera([0.0, 0.0, 4.0], [0.0; 3]).yfov(50),
        directional([0.3, -1.0, -0.2], sun),
        mirror("mirror", [0.9, 0.9, 0.9]),
        sphere("ball", 1.0).material("mirror"),
    ]);
    common::scene_from_toml(name, &toml)
}

#[test]
fn black_blinding_and_nan_inf_frames_stay_finite_and_sensible_on_every_backend() {
    let default = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    let black = mirror_under("tonemap_black", 0.0, 0.0);
    let blinding = mirror_under("tonemap_blinding", 1.0e6, 1.0e6);
    for backend in common::BACKENDS {
        let mut frames = Frames::new();
        // Tone mapping runs after the tracing passes: every mode and operator
        // on one backend, auto exposure with Reinhard on the others.
        let combos: Vec<(AutoExposure, ToneOperator)> = if backend == Backend::Compute {
            [AutoExposure::Off, AutoExposure::LogAverage, AutoExposure::Histogram]
                .into_iter()
                .flat_map(|m| ToneOperator::ALL.map(|o| (m, o)))
                .collect()
        } else {
            vec![
                (AutoExposure::LogAverage, ToneOperator::Reinhard),
                (AutoExposure::Off, ToneOperator::Reinhard),
            ]
        };
        for &(mode, op) in &combos {
            let settings = RenderSettings {
                backend,
                tone: ToneSettings { auto_exposure: mode, operator: op, ..Default::default() },
                ..auto(mode)
            };
            let what = format!("{backend:?}, {mode:?}, {op:?}");
            // Black: black, and a finite exposure.
            let f = frames.render("black", &black, &settings, &[]);
            assert!(f.ldr.chunks_exact(4).all(|p| p[..3] == [0, 0, 0]), "{what}: black frame not black");
            assert_eq!(f.bad_pixels, 0);
            if let Some(s) = f.exposure {
                assert!(s.exposure.is_finite() && s.exposure > 0.0, "{what}: black frame exposure {s:?}");
            }
            // Blinding, a sky pixel: auto-exposed to the key (mid grey
            // after the curve; reinhard-white maps the brightest pixel,
            // the sky, to white); fixed exposure 1: white. Never black.
            let f = frames.render("blinding", &blinding, &settings, &[]);
            let p = ldr(&f, 1, 1);
            let grey = mode != AutoExposure::Off && op != ToneOperator::ReinhardWhite;
            let ok = if grey {
                p[..3].iter().all(|&c| (60..=200).contains(&c))
            } else {
                p[..3].iter().all(|&c| c >= 250)
            };
            assert!(ok, "{what}: a sky of 1e6 is {p:?}");
            assert_eq!(f.bad_pixels, 0);
        }
        // NaN and Inf radiance: counted, magenta, and the rest of the frame
        // is what it is without them (left out of the exposure).
        let settings = RenderSettings { backend, ..auto(AutoExposure::LogAverage) };
        let clean = frames.render("default", &default, &settings, &[]);
        let bad = [
            ([3, 4], [f32::NAN, 0.0, 0.0]),
            ([40, 20], [f32::INFINITY, 1.0, 1.0]),
            ([63, 35], [f32::NEG_INFINITY, 0.0, 0.0]),
        ];
        let f = frames.render("default", &default, &settings, &bad);
        assert_eq!(f.bad_pixels, 3, "{backend:?}: bad pixels counted");
        let (e, e0) = (state(&f).exposure, state(&clean).exposure);
        // Three of 2304 pixels fewer in the average: a small change.
        assert!(
            e.is_finite() && ((e - e0) / e0).abs() < 0.02,
            "{backend:?}: exposure {e} vs {e0} without them"
        );
        for y in 0..f.height {
            for x in 0..f.width {
                let p = ldr(&f, x, y);
                if bad.iter().any(|(q, _)| *q == [x, y]) {
                    assert_eq!(p, [255, 0, 255, 255], "{backend:?}: bad pixel ({x}, {y}) not magenta");
                } else {
                    let q = ldr(&clean, x, y);
                    let d = (0..3).map(|c| (p[c] as i32 - q[c] as i32).abs()).max().unwrap();
                    assert!(d <= 2, "{backend:?}: pixel ({x}, {y}) {p:?}, without the bad pixels {q:?}");
                }
            }
        }
        // One pixel near the float maximum keeps the exposure finite and is white.
        let huge = [([10, 10], [3.0e38, 3.0e38, 3.0e38])];
        let f = frames.render("default", &default, &settings, &huge);
        let s = state(&f);
        assert!(
            s.exposure.is_finite() && s.exposure > 0.0 && s.log_average.is_finite(),
            "{backend:?}: {s:?}"
        );
        assert_eq!(ldr(&f, 10, 10)[..3], [255, 255, 255], "{backend:?}: 3e38 is white");
        assert_eq!(f.bad_pixels, 0);
        frames.finish();
    }
}
