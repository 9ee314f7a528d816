//! Pass `primary` (pure ray-traced mode): camera rays find the primary hits
//! and write them into the G-buffer targets `gbuffer` would fill, so every
//! later pass is the same in both modes (glsl/passes/primary.glsl).

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::{GB_ALBEDO, GB_HIT, GB_MATERIAL, GB_NORMAL};
use crate::render::frame::Access;
use crate::render::shading::{Mode, ShadingConfig};
use crate::vk::pipeline::Specialization;

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    let w = Access::StorageWrite;
    vec![
        TargetBinding::new(GB_ALBEDO, &gbuffer::ALBEDO, w),
        TargetBinding::new(GB_NORMAL, &gbuffer::NORMAL, w),
        TargetBinding::new(GB_MATERIAL, &gbuffer::MATERIAL, w),
        TargetBinding::new(GB_HIT, &gbuffer::HIT, w),
    ]
}

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    (c.mode == Mode::Hybrid)
        .then_some("hybrid mode: the visibility buffer (gbuffer or visibility trace) holds the primary hits")
}

pub const PASS: PassDesc = PassDesc {
    name: "primary",
    this_frame: super::every_frame,
    skip,
    uses: |c, _| fullscreen::uses(&io(c), true),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(i, "primary", io(i.config), Shader::Traced("primary"), &spec)
    },
};
