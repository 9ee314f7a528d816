//! Pass `reference` (`--reference-samples`): ray-traced diffuse environment light at the primary hit,
//! accumulated into its own target that `composite` reads in place of the ambient
//! (glsl/passes/reference.glsl; render/reference.rs drives the frames). Left out without the flag.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::REFERENCE_OUT;
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Per pixel the sum of the samples' radiance (rgb) and their count (a),
/// kept from frame to frame.
pub static ACCUMULATION: TargetDesc =
    TargetDesc::kept("reference accumulation", vk::Format::R32G32B32A32_SFLOAT);

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    io.push(TargetBinding::new(REFERENCE_OUT, &ACCUMULATION, Access::StorageWrite));
    io
}

pub fn skip(c: &ShadingConfig) -> Option<&'static str> {
    if c.debug_view {
        Some("a debug view shows the G-buffer instead")
    } else if !c.reference {
        Some("no --reference-samples")
    } else {
        None
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "reference",
    this_frame: super::every_frame,
    skip,
    uses: |c, _| fullscreen::accumulating_uses(&io(c), &ACCUMULATION),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(i, "reference", io(i.config), Shader::Traced("reference"), &spec)
    },
};
