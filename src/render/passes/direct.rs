//! Pass `direct`: direct light from every punctual light at the primary
//! hit, with transmittance shadow rays where the scene has shadow-casting
//! lights and occluders (glsl/passes/direct.glsl). Without shadows it
//! traces nothing and binds no tracer.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::DIRECT_OUT;
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Direct radiance per pixel (exact: `composite` adds it unrounded).
pub static DIRECT: TargetDesc = TargetDesc::new("direct light", vk::Format::R32G32B32A32_SFLOAT);

fn shadows(c: &ShadingConfig) -> bool {
    c.backend.is_some() && c.effects.shadows
}

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    io.push(TargetBinding::new(DIRECT_OUT, &DIRECT, Access::StorageWrite));
    io
}

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    c.debug_view.then_some("a debug view shows the G-buffer instead")
}

pub const PASS: PassDesc = PassDesc {
    name: "direct",
    this_frame: super::every_frame,
    skip,
    uses: |c, _| fullscreen::uses(&io(c), shadows(c)),
    create: |i: &Creation| {
        let shader =
            if shadows(i.config) { Shader::Traced("direct") } else { Shader::Compute("direct.comp") };
        FullScreen::create(
            i,
            "direct",
            io(i.config),
            shader,
            &Specialization::new(&i.config.specialization()),
        )
    },
};
