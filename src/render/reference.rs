//! The ray-traced reference for diffuse environment light
//! (`--reference-samples N`): the `reference` pass (passes/reference.rs)
//! accumulates REFERENCE_SAMPLES_PER_FRAME hemisphere samples per pixel per
//! frame; here are its settings, when the accumulation starts over, and the
//! loop that renders the ⌈N/S⌉ frames of a converged image.

use anyhow::Result;

use super::{FrameOutput, RenderSettings, Renderer};
use crate::gpu::shared::REFERENCE_SAMPLES_PER_FRAME;
use crate::gpu::types::GpuFrame;
use crate::scene::{Camera, Scene};
use crate::vk::Context;

/// What the reference integrates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceSettings {
    /// Samples per pixel of the converged image (rounded up to whole frames).
    pub samples: u32,
    /// Rays per path: 1 = environment light with visibility, K > 1 adds
    /// K - 1 diffuse bounces.
    pub bounces: u32,
}

impl ReferenceSettings {
    /// Frames that reach `samples` at REFERENCE_SAMPLES_PER_FRAME a frame.
    pub fn frames(&self) -> u32 {
        self.samples.div_ceil(REFERENCE_SAMPLES_PER_FRAME).max(1)
    }
}

/// The accumulation's history: frames accumulated since the last change of
/// what the image shows (camera, environment, path length, targets).
#[derive(Clone, Debug, Default)]
pub struct Accumulation {
    frames: u32,
    key: Option<Vec<u32>>,
}

impl Accumulation {
    /// Starts over at the next frame (new targets, a moved scene).
    pub fn reset(&mut self) {
        *self = Accumulation::default();
    }

    /// Frames accumulated before this one.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The frame's `reference_frame` uniform for `frame` (the others
    /// filled): 0 when what it shows differs from the accumulated frames'.
    pub fn next(&mut self, frame: &GpuFrame) -> u32 {
        // Everything the image depends on; not the frame counter, exposure
        // or tone mapping.
        let f = frame;
        let key: Vec<u32> =
            [&f.view_proj[..], &f.camera_pos, &f.env_color, &[f.env_intensity, f.env_rotation]]
                .concat()
                .iter()
                .map(|v| v.to_bits())
                .chain([f.reference_bounces, f.resolution[0], f.resolution[1], f.light_count])
                .collect();
        if self.key.as_ref() != Some(&key) {
            self.frames = 0;
            self.key = Some(key);
        }
        let n = self.frames;
        self.frames += 1;
        n
    }
}

/// Renders `settings.reference`'s frames of one view (from scratch) and
/// returns the last: the converged image. Logs progress every few frames
/// (a software device takes minutes for N = 1024). Without a reference in
/// `settings` it is one `render`.
pub fn render_converged(
    renderer: &mut Renderer,
    ctx: &Context,
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
) -> Result<FrameOutput> {
    let Some(r) = settings.reference else { return renderer.render(ctx, scene, camera, settings) };
    renderer.reset_reference();
    let frames = r.frames();
    let start = std::time::Instant::now();
    let mut last = std::time::Instant::now();
    let mut out = renderer.render(ctx, scene, camera, settings)?;
    for i in 1..frames {
        if last.elapsed().as_secs_f64() >= 5.0 {
            last = std::time::Instant::now();
            log::info!(
                "reference: frame {i}/{frames} ({} samples per pixel), {:.0} s",
                i * REFERENCE_SAMPLES_PER_FRAME,
                start.elapsed().as_secs_f64()
            );
        }
        out = renderer.render(ctx, scene, camera, settings)?;
    }
    log::info!(
        "reference: {} samples per pixel in {frames} frames, {} bounce(s), {:.1} s",
        frames * REFERENCE_SAMPLES_PER_FRAME,
        r.bounces,
        start.elapsed().as_secs_f64()
    );
    Ok(out)
}
