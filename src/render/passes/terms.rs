//! Pass `terms` (report/attribution.rs): per pixel, the path-traced estimate of the selected terms the
//! hybrid approximates or leaves out (`TERM_*`), accumulated into a target `composite` adds in place of
//! its own shading of those terms (glsl/passes/terms.glsl). Only with `RenderSettings::terms`; never in a
//! debug view or beside the ambient reference.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{direct, gbuffer, Creation, PassDesc};
use crate::gpu::shared::{DIRECT_IN, TERMS_OUT};
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Per pixel the sum of the samples (rgb) and their count
/// (a), kept from frame to frame.
pub static ACCUMULATION: TargetDesc = TargetDesc::kept("terms accumulation", vk::Format::R32G32B32A32_SFLOAT);

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    // The hybrid's direct light, which the caustics term corrects.
    io.push(TargetBinding::new(DIRECT_IN, &direct::DIRECT, Access::StorageRead));
    io.push(TargetBinding::new(TERMS_OUT, &ACCUMULATION, Access::StorageWrite));
    io
}

pub fn skip(c: &ShadingConfig) -> Option<&'static str> {
    if c.terms {
        None
    } else {
        Some("no attribution terms (report only)")
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "terms",
    this_frame: super::every_frame,
    skip,
    uses: |c, _| fullscreen::accumulating_uses(&io(c), &ACCUMULATION),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(i, "terms", io(i.config), Shader::Traced("terms"), &spec)
    },
};
