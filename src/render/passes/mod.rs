//! The frame's passes, one module each, in frame order. A pass module
//! exports a `PASS: PassDesc`: when it is left out (and why), what it reads
//! and writes, and how to build it. Adding a pass is one module plus one
//! line in `FRAME`.

pub mod antialias;
pub mod compacted;
pub mod composite;
pub mod direct;
pub mod edge_aa;
pub mod fullscreen;
pub mod fxaa;
pub mod gbuffer;
pub mod gbuffer_resolve;
pub mod heuristic;
pub mod luminance;
pub mod path;
pub mod primary;
pub mod reference;
pub mod shadow_map;
pub mod specular;
pub mod terms;
pub mod tonemap;
pub mod visibility_trace;

use anyhow::Result;
use ash::vk;

use super::cull::DrawList;
use super::frame::Use;
use super::shading::ShadingConfig;
use super::targets::Targets;
use super::tracer::Tracer;
use crate::gpu::GpuScene;
use crate::vk::Context;

/// The frame, top to bottom (DESIGN.md's data flow): primary hits (raster
/// or traced visibility buffer + resolve, or camera rays) -> per-object
/// statistics for the budget -> the budget's fallback shadow maps -> direct
/// light -> the ambient reference (with --reference-samples) -> the
/// report's attribution terms -> reflection/refraction chain -> composite
/// -> luminance (auto exposure) -> tone map -> anti-aliasing (at most one
/// technique). The scene update (skinning, refit, top level) comes before
/// it, recorded by `Renderer` and the tracer.
pub const FRAME: &[PassDesc] = &[
    gbuffer::PASS,
    visibility_trace::PASS,
    gbuffer_resolve::PASS,
    primary::PASS,
    heuristic::PASS,
    shadow_map::PASS,
    direct::PASS,
    reference::PASS,
    terms::PASS,
    specular::PASS,
    composite::PASS,
    luminance::PASS,
    tonemap::PASS,
    edge_aa::PASS,
    fxaa::PASS,
];

/// The frame of `--mode path` (DESIGN.md: path -> accumulate -> tone map):
/// the path tracer writes the radiance the same luminance and tone mapping
/// read; no G-buffer, and no anti-aliasing (the paths' jittered camera rays
/// already integrate each pixel's area).
pub const PATH_FRAME: &[PassDesc] = &[path::PASS, luminance::PASS, tonemap::PASS];

/// The pass list of a frame of this configuration.
pub fn frame(config: &ShadingConfig) -> &'static [PassDesc] {
    match config.mode {
        super::shading::Mode::Path => PATH_FRAME,
        _ => FRAME,
    }
}

/// What a pass is created from.
pub struct Creation<'a> {
    pub ctx: &'a Context,
    pub config: &'a ShadingConfig,
    pub gpu: &'a GpuScene,
    pub targets: &'a Targets,
    pub tracer: Option<&'a dyn Tracer>,
}

/// What a pass records with.
pub struct Recording<'a> {
    pub ctx: &'a Context,
    pub gpu: &'a GpuScene,
    pub targets: &'a Targets,
    pub tracer: Option<&'a dyn Tracer>,
    /// The frame's G-buffer draws after frustum culling (render/cull.rs).
    pub draws: &'a DrawList,
}

pub struct PassDesc {
    pub name: &'static str,
    /// Why the pass is left out of a frame with this configuration (None: it runs).
    pub skip: fn(&ShadingConfig) -> Option<&'static str>,
    /// The resources it reads and writes in this configuration.
    pub uses: fn(&ShadingConfig) -> Vec<Use>,
    pub create: fn(&Creation) -> Result<Box<dyn Pass>>,
}

pub trait Pass {
    /// The shader stage its resource accesses happen in (for barriers).
    fn stage(&self) -> vk::PipelineStageFlags2;
    fn record(&self, cx: &Recording, cmd: vk::CommandBuffer);
    /// Points the pass at new targets (after a resize).
    fn bind(&self, ctx: &Context, targets: &Targets);
    fn destroy(&mut self, ctx: &Context);
}
