//! Rendering and timing one setting: an optional ray-counting frame,
//! warm-up frames (the first compiles the setting's pipelines), then the
//! timed frames, whose GPU timestamps give the median and p95 frame time
//! and the per-pass medians.

use anyhow::Result;
use ash::vk as avk;

use super::knobs::Variant;
use super::metrics::{HdrImage, LdrImage};
use crate::render::shading::Effects;
use crate::render::Renderer;
use crate::scene::{Camera, Scene};
use crate::vk::Context;

/// GPU time of a setting over its timed frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// Frame time (sum of the passes, readback excluded), median and p95.
    pub median: f64,
    pub p95: f64,
    /// Median ms of each pass, in frame order.
    pub passes: Vec<(&'static str, f64)>,
    pub frames: usize,
}

impl Timing {
    /// Median ms of pass `name`, if it ran.
    pub fn pass(&self, name: &str) -> Option<f64> {
        self.passes.iter().find(|(n, _)| *n == name).map(|(_, ms)| *ms)
    }

    /// Median ms of the anti-aliasing pass, if one ran.
    pub fn aa_pass(&self) -> Option<f64> {
        AA_PASSES.iter().find_map(|p| self.pass(p))
    }
}

/// The anti-aliasing passes (at most one runs).
pub const AA_PASSES: [&str; 2] = ["edge aa", "fxaa"];

/// A rendered and timed setting.
pub struct Measured {
    pub variant: Variant,
    /// The resolved configuration (mode, backend, effects that ran).
    pub config: String,
    /// The backend that traced rays, or "none".
    pub backend: String,
    pub width: u32,
    pub height: u32,
    pub timing: Timing,
    /// Camera, shadow and secondary rays of one frame, when counted.
    pub rays: Option<[u32; 3]>,
    /// The last timed frame's radiance (at the variant's own size).
    pub image: HdrImage,
    /// Its final 8-bit image (tone-mapped, anti-aliased per the variant).
    pub ldr: LdrImage,
    /// Pixels whose radiance was NaN or Inf (set to 0 in `image`).
    pub non_finite: usize,
    /// What auto exposure measured in it (None: fixed exposure).
    pub exposure: Option<crate::render::tone::ExposureState>,
}

impl Measured {
    /// Median ms of pass `name` (NaN when it did not run).
    pub fn pass_ms(&self, name: &str) -> f64 {
        self.timing.pass(name).unwrap_or(f64::NAN)
    }
}

/// The median (upper one of an even count, like `bench`) and the p95
/// (nearest rank) of `v`.
pub fn median_p95(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let rank = ((0.95 * s.len() as f64).ceil() as usize).clamp(1, s.len());
    (s[s.len() / 2], s[rank - 1])
}

/// The frame extent of `variant` for a report at `width` x `height`.
pub fn scaled_extent(width: u32, height: u32, scale: f32) -> avk::Extent2D {
    let s = |v: u32| ((v as f32 * scale).round() as u32).max(1);
    avk::Extent2D { width: s(width), height: s(height) }
}

/// Renders `variant` with `renderer` (made for its extent): a counted
/// frame when `count_rays`, `warmup` frames (at least one), then `frames`
/// timed ones.
#[allow(clippy::too_many_arguments)]
pub fn measure(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    variant: &Variant,
    warmup: usize,
    frames: usize,
    count_rays: bool,
) -> Result<Measured> {
    let settings = variant.settings;
    let rays = if count_rays { Some(count_frame(ctx, renderer, scene, camera, &settings)?) } else { None };
    for _ in 0..warmup.max(1) {
        renderer.render(ctx, scene, camera, &settings)?;
    }
    let mut times = Times::default();
    let mut last = None;
    for _ in 0..frames.max(1) {
        let out = renderer.render(ctx, scene, camera, &settings)?;
        times.add(&out.timings, &[]);
        last = Some(out);
    }
    Ok(finish(renderer, variant, times, rays, last.expect("at least one timed frame")))
}

/// The animation a variant with an acceleration-structure update plays.
#[derive(Clone, Copy, Debug)]
pub struct Playback {
    pub animation: usize,
    /// The last frame's time (the report's --time), seconds.
    pub end: f32,
    pub fps: f32,
}

/// Measures a variant whose acceleration structures follow an animation (`variant.accel`): its own
/// renderer, built on the first of `warmup + frames` poses one frame apart ending at `playback.end`,
/// updates the structures the variant's way every frame. Timed frames include the update (and a
/// rebuild's wall time); the image is the last frame's, after `warmup + frames - 1` updates.
#[allow(clippy::too_many_arguments)]
pub fn measure_animated(
    ctx: &Context,
    scene: &Scene,
    playback: Playback,
    camera: &Camera,
    variant: &Variant,
    extent: avk::Extent2D,
    (warmup, frames): (usize, usize),
    count_rays: bool,
) -> Result<Measured> {
    let accel = variant.accel.expect("an animated variant");
    let n = warmup.max(1) + frames.max(1);
    let step = 1.0 / playback.fps.max(1e-3);
    let time = |i: usize| playback.end - (n - 1 - i) as f32 * step;
    let mut scene = scene.clone();
    scene.animate(playback.animation, time(0));
    let mut renderer = Renderer::new(ctx, &scene, extent)?;
    let result = (|| {
        let settings = variant.settings;
        let rays =
            if count_rays { Some(count_frame(ctx, &mut renderer, &scene, camera, &settings)?) } else { None };
        let mut times = Times::default();
        let mut last = None;
        for i in 0..n {
            scene.animate(playback.animation, time(i));
            accel.update(ctx, &mut renderer, &scene)?;
            let out = renderer.render(ctx, &scene, camera, &settings)?;
            if i >= n - frames.max(1) {
                times.add(&out.timings, &renderer.update.timings);
                last = Some(out);
            }
        }
        Ok(finish(&renderer, variant, times, rays, last.expect("at least one timed frame")))
    })();
    renderer.destroy(ctx);
    result
}

/// One frame that counts rays by kind (camera, shadow, secondary).
fn count_frame(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    settings: &crate::render::RenderSettings,
) -> Result<[u32; 3]> {
    let counting = crate::render::RenderSettings {
        effects: Effects { count_rays: true, ..settings.effects },
        ..*settings
    };
    Ok(renderer.render(ctx, scene, camera, &counting)?.ray_counts)
}

/// Per-frame totals and per-pass times of the timed frames.
#[derive(Default)]
struct Times {
    totals: Vec<f64>,
    per_pass: Vec<(&'static str, Vec<f64>)>,
}

impl Times {
    /// One frame: its update passes (if any) and its frame passes; the
    /// readback is not part of the frame.
    fn add(&mut self, frame: &[(&'static str, f64)], update: &[(&'static str, f64)]) {
        let mut total = 0.0;
        for &(name, ms) in update.iter().chain(frame).filter(|(n, _)| *n != "readback") {
            total += ms;
            match self.per_pass.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => v.push(ms),
                None => self.per_pass.push((name, vec![ms])),
            }
        }
        self.totals.push(total);
    }
}

fn finish(
    renderer: &Renderer,
    variant: &Variant,
    times: Times,
    rays: Option<[u32; 3]>,
    out: crate::render::FrameOutput,
) -> Measured {
    if let Some(w) = out.truncation_warning() {
        log::warn!("{w}");
    }
    let (median, p95) = median_p95(&times.totals);
    let config = renderer.shading_config();
    let (image, non_finite) = HdrImage::from_rgba(out.width, out.height, &out.hdr);
    if non_finite > 0 {
        log::warn!("{non_finite} pixel(s) with NaN or Inf radiance; compared as 0");
    }
    Measured {
        variant: *variant,
        config: config.map(|c| c.describe()).unwrap_or_default(),
        backend: config
            .and_then(|c| c.backend)
            .map(|b| format!("{b:?}").to_lowercase())
            .unwrap_or_else(|| "none".into()),
        width: out.width,
        height: out.height,
        timing: Timing {
            median,
            p95,
            passes: times.per_pass.into_iter().map(|(n, v)| (n, median_p95(&v).0)).collect(),
            frames: times.totals.len(),
        },
        rays,
        image,
        ldr: LdrImage { width: out.width, height: out.height, rgb: out.rgb8().into_raw() },
        non_finite,
        exposure: out.exposure,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_p95_by_rank() {
        let v: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(median_p95(&v), (11.0, 19.0));
        assert_eq!(median_p95(&[3.0, 1.0, 2.0, 5.0, 4.0]), (3.0, 5.0));
        assert!(median_p95(&[]).0.is_nan());
        assert_eq!(scaled_extent(32, 18, 0.5), avk::Extent2D { width: 16, height: 9 });
        assert_eq!(scaled_extent(3, 1, 0.1), avk::Extent2D { width: 1, height: 1 });
    }
}
