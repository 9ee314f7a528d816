//! Pass `specular`: the reflection / refraction chain from the primary hit (glsl/passes/specular.glsl),
//! traced only for pixels whose hit spawns a branch (compacted.rs). Left out when nothing mirrors or
//! transmits, or both effects are off.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{compacted, gbuffer, Creation, PassDesc};
use crate::gpu::shared::SPECULAR_OUT;
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Radiance the chain brings back per pixel.
pub static SPECULAR: TargetDesc = TargetDesc::new("specular chain", vk::Format::R32G32B32A32_SFLOAT);

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    io.push(TargetBinding::new(SPECULAR_OUT, &SPECULAR, Access::StorageWrite));
    io.push(compacted::list_io());
    io
}

pub fn skip(c: &ShadingConfig) -> Option<&'static str> {
    if c.debug_view {
        Some("a debug view shows the G-buffer instead")
    } else if !c.needs.mirrors && !c.needs.refractions {
        Some("no mirror or transmissive material")
    } else if !(c.effects.refractions || c.effects.reflections && c.needs.mirrors) {
        Some("reflections and refractions switched off")
    } else {
        None
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "specular",
    this_frame: super::every_frame,
    skip,
    uses: |c, _| fullscreen::uses(&io(c), true),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(
            i,
            "specular",
            io(i.config),
            Shader::Listed { select: "specular_select.comp", traced: "specular" },
            &spec,
        )
    },
};
