//! Pass `glossy`: one GGX visible-normal reflection ray per glossy pixel (glsl/passes/glossy.glsl), the
//! split-sum environment's correction where the lobe meets geometry; `glossy_filter` denoises it. Traced
//! only for the listed pixels (compacted.rs). Left out when no material is glossy (MIRROR_ROUGHNESS <
//! roughness <= GLOSSY_ROUGHNESS) or reflections are off.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{compacted, gbuffer, Creation, PassDesc};
use crate::gpu::shared::GLOSSY_OUT;
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Per pixel the lobe sample's correction (rgb) and the camera distance (a; 0: no sample).
pub static GLOSSY: TargetDesc = TargetDesc::new("glossy sample", vk::Format::R32G32B32A32_SFLOAT);

fn io() -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    io.push(TargetBinding::new(GLOSSY_OUT, &GLOSSY, Access::StorageWrite));
    io.push(compacted::list_io());
    io
}

pub fn skip(c: &ShadingConfig) -> Option<&'static str> {
    if c.debug_view {
        Some("a debug view shows the G-buffer instead")
    } else if !c.needs.glossy {
        Some("no glossy material")
    } else if !c.effects.reflections || c.backend.is_none() {
        Some("reflections switched off")
    } else if c.terms {
        // The attribution (report/attribution.rs) replaces the split sum's environment and the lobe's hits
        // term by term, against the frame without this correction.
        Some("the attribution terms measure the split-sum frame")
    } else {
        None
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "glossy",
    this_frame: super::every_frame,
    skip,
    uses: |_, _| fullscreen::uses(&io(), true),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(
            i,
            "glossy",
            io(),
            Shader::Listed { select: "glossy_select.comp", traced: "glossy" },
            &spec,
        )
    },
};
