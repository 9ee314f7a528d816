//! Pass `heuristic`: per-object covered pixels and bounds for the budget (render/budget), from the
//! G-buffer's hit ids (glsl/heuristic.comp); the host selects the next frame's objects from them.
//! Left out without `--budget`.

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::{GB_HIT, HEURISTIC_BLOCK_H, HEURISTIC_BLOCK_W};
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
        // Per block and subgroup where the device reduces across lanes, else per pixel and tile in
        // shared memory.
        let (shader, group) = if i.ctx.caps.subgroup_arithmetic {
            ("heuristic.comp", [8 * HEURISTIC_BLOCK_W, 8 * HEURISTIC_BLOCK_H])
        } else {
            ("heuristic_shared", fullscreen::PIXEL_GROUP)
        };
        let spec = Specialization::new(&[]);
        FullScreen::create_grouped(i, "heuristic", io(), Shader::Compute(shader), &spec, group)
    },
};
