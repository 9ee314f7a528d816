//! The ray-traced reference for diffuse environment light (`--reference-samples N`): the `reference`
//! pass (passes/reference.rs) accumulates REFERENCE_SAMPLES_PER_FRAME hemisphere samples per pixel per
//! frame; here is when the accumulation starts over and the loop that renders a converged image's
//! ⌈N/S⌉ frames (settings: settings.rs `ReferenceSettings`).

use anyhow::Result;

use super::shading::Mode;
use super::{FrameOutput, RenderSettings, Renderer};
use crate::gpu::shared::{PATH_SAMPLES_PER_FRAME, REFERENCE_SAMPLES_PER_FRAME};
use crate::gpu::types::GpuFrame;
use crate::scene::{Camera, Scene};
use crate::vk::Context;

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

    /// The frame's `accum_frame` uniform for `frame` (the others
    /// filled): 0 when what it shows differs from the accumulated frames'.
    pub fn next(&mut self, frame: &GpuFrame) -> u32 {
        // Everything the image depends on; not the frame counter, exposure or tone mapping.
        let f = frame;
        let key: Vec<u32> =
            [&f.view_proj[..], &f.camera_pos, &f.env_color, &[f.env_intensity, f.env_rotation, f.path_clamp]]
                .concat()
                .iter()
                .map(|v| v.to_bits())
                .chain([f.accum_bounces, f.resolution[0], f.resolution[1], f.light_count, f.flags])
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

/// Renders one view's converged image from scratch, the path tracer's (`--mode path`) or the ambient
/// reference's (`settings.reference`), and returns the last frame; without either it is one `render`.
/// Logs progress every few seconds (a software device takes minutes for N = 1024).
pub fn render_converged(
    renderer: &mut Renderer,
    ctx: &Context,
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
) -> Result<FrameOutput> {
    let (frames, per_frame, what) = match (settings.mode, settings.reference) {
        (Mode::Path, _) => (settings.path.frames(), PATH_SAMPLES_PER_FRAME, "path"),
        (_, Some(r)) => (r.frames(), REFERENCE_SAMPLES_PER_FRAME, "reference"),
        _ => return renderer.render(ctx, scene, camera, settings),
    };
    renderer.reset_reference();
    let start = std::time::Instant::now();
    let mut last = std::time::Instant::now();
    let mut out = renderer.render(ctx, scene, camera, settings)?;
    for i in 1..frames {
        if last.elapsed().as_secs_f64() >= 5.0 {
            last = std::time::Instant::now();
            let (done, spp) = (100 * i / frames, i * per_frame);
            let secs = start.elapsed().as_secs_f64();
            log::info!("{what}: {done}% ({spp} samples per pixel, frame {i}/{frames}), {secs:.0} s");
        }
        out = renderer.render(ctx, scene, camera, settings)?;
    }
    let how = match (settings.mode, settings.reference) {
        (Mode::Path, _) => format!(
            "at most {} bounces{}",
            settings.path.max_bounces,
            settings.path.clamp.map_or(String::new(), |c| format!(", radiance clamped to {c} (biased)"))
        ),
        (_, r) => format!("{} bounce(s)", r.map_or(0, |r| r.bounces)),
    };
    log::info!(
        "{what}: {} samples per pixel in {frames} frames, {how}, {:.1} s",
        frames * per_frame,
        start.elapsed().as_secs_f64()
    );
    Ok(out)
}
