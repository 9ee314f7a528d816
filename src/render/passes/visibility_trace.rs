//! Pass `visibility_trace` (hybrid mode, traced primary visibility): camera rays traced exactly as
//! `primary` does write the hit ids the raster `gbuffer` would and resolve the material targets with
//! `gbuffer_resolve`'s code, so that pass is left out (glsl/passes/visibility_trace.glsl). No depth
//! buffer: only the raster's depth test reads it. On lavapipe a mesh of many small triangles
//! rasterizes slower than it traces (bench/results/lavapipe-2core-vm-raster.md), so
//! `--primary-visibility auto` measures both (render/visibility.rs).

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::{GB_ALBEDO, GB_HIT, GB_MATERIAL, GB_NORMAL};
use crate::render::frame::Access;
use crate::render::settings::PrimaryVisibility;
use crate::render::shading::{Mode, ShadingConfig};
use crate::vk::pipeline::Specialization;

fn io() -> Vec<TargetBinding> {
    let w = Access::StorageWrite;
    vec![
        TargetBinding::new(GB_HIT, &gbuffer::HIT, w),
        TargetBinding::new(GB_ALBEDO, &gbuffer::ALBEDO, w),
        TargetBinding::new(GB_NORMAL, &gbuffer::NORMAL, w),
        TargetBinding::new(GB_MATERIAL, &gbuffer::MATERIAL, w),
    ]
}

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    match (c.mode, c.visibility) {
        (Mode::Rt, _) => Some("pure ray-traced mode: pass primary traces the camera rays"),
        (_, PrimaryVisibility::Raster) => Some("--primary-visibility raster: pass gbuffer rasterizes them"),
        _ => None,
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "visibility trace",
    this_frame: |f| {
        (f.visibility == Some(super::Technique::Raster)).then_some("raster visibility this frame")
    },
    skip,
    uses: |_, _| fullscreen::uses(&io(), true),
    create: |i: &Creation| {
        // The same specialization as `primary`: ray counting follows it.
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(i, "visibility trace", io(), Shader::Traced("visibility_trace"), &spec)
    },
};
