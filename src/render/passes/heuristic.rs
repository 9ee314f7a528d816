//! Pass `heuristic`: per-object covered pixels and bounds for the budget (render/budget), from the
//! G-buffer's hit ids (glsl/heuristic.comp); the host selects the next frame's objects from them.
//! Left out without `--budget`.

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::GB_HIT;
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::shading::ShadingConfig;
use crate::vk::pipeline::Specialization;

fn io() -> Vec<TargetBinding> {
    vec![TargetBinding::new(GB_HIT, &gbuffer::HIT, Access::Sampled)]
}

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    (!c.budget).then_some("no --budget: every object gets ray-traced effects")
}

pub const PASS: PassDesc = PassDesc {
    name: "heuristic",
    this_frame: super::every_frame,
    skip,
    uses: |_, _| {
        let mut u = fullscreen::uses(&io(), false);
        u.push(Use::buffer(SharedBuffer::Budget, Access::ShaderWrite));
        u
    },
    create: |i: &Creation| {
        // Per subgroup where the device reduces across lanes, else per tile in shared memory.
        let shader = if i.ctx.caps.subgroup_arithmetic { "heuristic.comp" } else { "heuristic_shared" };
        FullScreen::create(i, "heuristic", io(), Shader::Compute(shader), &Specialization::new(&[]))
    },
};
