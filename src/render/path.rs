//! The path-traced ground truth's settings (`--mode path`, pass `path`). Its converged frames are
//! rendered by `reference::render_converged`, as the ambient reference's are.

use crate::gpu::shared::PATH_SAMPLES_PER_FRAME;

/// What the path tracer integrates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Paths per pixel of the converged image (rounded up to whole frames).
    pub samples: u32,
    /// Longest path in bounces; Russian roulette ends most paths long
    /// before (a cap only truncates energy that survived every roulette).
    pub max_bounces: u32,
    /// A sample's radiance is scaled down to at most this (max channel):
    /// an explicit bias against fireflies; None, the unbiased estimate.
    pub clamp: Option<f32>,
}

impl PathSettings {
    pub const DEFAULT_SAMPLES: u32 = 64;
    pub const DEFAULT_MAX_BOUNCES: u32 = 32;

    /// Frames that reach `samples` at PATH_SAMPLES_PER_FRAME a frame.
    pub fn frames(&self) -> u32 {
        self.samples.div_ceil(PATH_SAMPLES_PER_FRAME).max(1)
    }
}

impl Default for PathSettings {
    fn default() -> Self {
        PathSettings { samples: Self::DEFAULT_SAMPLES, max_bounces: Self::DEFAULT_MAX_BOUNCES, clamp: None }
    }
}
