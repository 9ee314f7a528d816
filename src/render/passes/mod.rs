//! The frame's passes, one module each, in frame order. Each exports a `PASS: PassDesc` (when it is
//! left out and why, what it reads and writes, how to build it); a new pass is one module plus one
//! line in `FRAME`.

pub mod antialias;
pub mod ao;
pub mod ao_filter;
pub mod compacted;
pub mod composite;
pub mod direct;
pub mod edge_aa;
pub mod fullscreen;
pub mod fxaa;
pub mod gbuffer;
pub mod gbuffer_resolve;
pub mod glossy;
pub mod glossy_filter;
pub mod glossy_temporal;
pub mod heuristic;
pub mod inject;
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
use super::uses::TargetDesc;
use crate::gpu::GpuScene;
use crate::vk::Context;
use inject::Injected;

/// The frame (DESIGN.md's data flow): primary hits (raster or traced visibility + resolve, or camera
/// rays) -> budget statistics -> fallback shadow maps -> direct -> ambient visibility and its filter ->
/// ambient reference -> attribution
/// terms -> specular chain -> glossy reflections, their history and filter -> composite -> luminance -> tone map -> anti-aliasing (at most one). The
/// scene update (skinning, refit, top level) is recorded before it by `Renderer` and the tracer.
pub const FRAME: &[PassDesc] = &[
    gbuffer::PASS,
    visibility_trace::PASS,
    gbuffer_resolve::PASS,
    primary::PASS,
    heuristic::PASS,
    shadow_map::PASS,
    direct::PASS,
    ao::PASS,
    ao_filter::PASS,
    reference::PASS,
    terms::PASS,
    specular::PASS,
    glossy::PASS,
    glossy_temporal::PASS,
    glossy_filter::PASS,
    composite::PASS,
    inject::PASS,
    luminance::PASS,
    tonemap::PASS,
    edge_aa::PASS,
    fxaa::PASS,
];

/// `--mode path` (DESIGN.md: path -> accumulate -> tone map): no G-buffer and no anti-aliasing (the
/// jittered camera rays already integrate each pixel's area).
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
    /// What the passes before it in this frame write.
    pub upstream: &'a Upstream,
}

/// Targets the frame's passes so far write: consumers take input handles from here (None: nothing
/// makes it) instead of re-deriving whether the producer runs.
#[derive(Clone, Default)]
pub struct Upstream {
    written: Vec<&'static TargetDesc>,
}

impl Upstream {
    /// The handle of `target` if a pass before this one writes it.
    pub fn get(&self, target: &'static TargetDesc) -> Option<&'static TargetDesc> {
        self.written.iter().copied().find(|t| std::ptr::eq(*t, target))
    }

    /// Adds what a pass writes.
    pub fn add(&mut self, uses: &[Use]) {
        for u in uses.iter().filter(|u| u.access.writes()) {
            if let super::uses::Resource::Image(t) = u.resource {
                if self.get(t).is_none() {
                    self.written.push(t);
                }
            }
        }
    }
}

/// Hybrid mode's two primary-visibility techniques, by the pass that
/// implements each (render/visibility.rs chooses between them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Technique {
    Raster,
    Traced,
}

impl Technique {
    pub fn pass(self) -> &'static str {
        match self {
            Technique::Raster => gbuffer::PASS.name,
            Technique::Traced => visibility_trace::PASS.name,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Technique::Raster => "raster",
            Technique::Traced => "traced",
        }
    }
    pub fn index(self) -> usize {
        self as usize
    }
    pub fn other(self) -> Technique {
        match self {
            Technique::Raster => Technique::Traced,
            Technique::Traced => Technique::Raster,
        }
    }
}

/// What varies from frame to frame within one configuration, which some
/// passes record or not by (`PassDesc::this_frame`).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameState {
    /// Why the budget's fallback shadow maps are not needed this frame.
    pub shadow_maps_left_out: Option<&'static str>,
    /// The primary-visibility technique this frame records (auto: raster
    /// and traced frames alternate while measuring).
    pub visibility: Option<Technique>,
}

/// `this_frame` of a pass that records in every frame of its configuration.
pub fn every_frame(_: &FrameState) -> Option<&'static str> {
    None
}

/// What a pass records with.
pub struct Recording<'a> {
    pub ctx: &'a Context,
    pub gpu: &'a GpuScene,
    pub targets: &'a Targets,
    pub tracer: Option<&'a dyn Tracer>,
    /// The frame's G-buffer draws after frustum culling (render/cull.rs).
    pub draws: &'a DrawList,
    /// The pixels the armed fault injection overwrites (tests only).
    pub injected: &'a [Injected],
}

pub struct PassDesc {
    pub name: &'static str,
    /// Why the pass is left out of a frame with this configuration (None:
    /// it is created).
    pub skip: fn(&ShadingConfig) -> Option<&'static str>,
    /// Why a created pass is left out of this frame (None: it records).
    pub this_frame: fn(&FrameState) -> Option<&'static str>,
    /// The resources it reads and writes in this configuration, given what
    /// the passes before it write.
    pub uses: fn(&ShadingConfig, &Upstream) -> Vec<Use>,
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

/// A pass under construction is destroyed like any pass (`vk::built`).
impl<P: Pass> crate::vk::Destroy for P {
    fn destroy(&mut self, ctx: &Context) {
        Pass::destroy(self, ctx)
    }
}
