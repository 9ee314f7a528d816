//! Pass `glossy temporal`: this frame's glossy sample blended into the reprojected history of the last
//! frames (glsl/glossy_temporal.comp); `glossy filter` filters the blend and keeps it as the next
//! frame's history. Runs where `glossy` does with temporal reuse on (the viewer): `render`, `bench`,
//! `report` and the tests render one-sample frames, and the filter reads the sample itself.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, glossy, Creation, PassDesc};
use crate::gpu::shared::{GLOSSY_ACCUM, GLOSSY_HISTORY, GLOSSY_IN};
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// The last frame's blend (rgb) at the camera distance it was seen from (a; 0: none), kept across
/// frames; valid from the second frame of a configuration and size on (FRAME_GLOSSY_HISTORY).
pub static HISTORY: TargetDesc = TargetDesc::kept("glossy history", vk::Format::R32G32B32A32_SFLOAT);
/// This frame's blend, laid out like `glossy::GLOSSY`.
pub static BLEND: TargetDesc = TargetDesc::new("glossy blend", vk::Format::R32G32B32A32_SFLOAT);

fn io() -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    io.push(TargetBinding::new(GLOSSY_IN, &glossy::GLOSSY, Access::StorageRead));
    io.push(TargetBinding::new(GLOSSY_HISTORY, &HISTORY, Access::StorageRead));
    io.push(TargetBinding::new(GLOSSY_ACCUM, &BLEND, Access::StorageWrite));
    io
}

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    glossy::skip(c).or((!c.glossy_temporal).then_some("no temporal reuse: each frame is a one-sample frame"))
}

pub const PASS: PassDesc = PassDesc {
    name: "glossy temporal",
    this_frame: super::every_frame,
    skip,
    uses: |_, _| fullscreen::uses(&io(), false),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(i, "glossy temporal", io(), Shader::Compute("glossy_temporal.comp"), &spec)
    },
};
