//! Pass `glossy filter`: the glossy correction (`glossy temporal`'s blend) denoised by a joint bilateral
//! filter guided by the G-buffer and scaled by the lobe's albedo, the blend kept as the next frame's
//! history, plus the specular chain where `specular` runs
//! (glsl/glossy_filter.comp): `composite` reads its output as the frame's one specular input. Runs
//! exactly when `glossy` does.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, glossy, glossy_temporal, specular, Creation, PassDesc, Upstream};
use crate::gpu::shared::{GLOSSY_HISTORY, GLOSSY_IN, REFLECTED_OUT, SPECULAR_IN};
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Reflected and refracted radiance at the primary hit beyond the split sum: the filtered glossy term and
/// the specular chain.
pub static REFLECTED: TargetDesc = TargetDesc::new("reflected radiance", vk::Format::R32G32B32A32_SFLOAT);

fn io(up: &Upstream) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    io.push(TargetBinding::new(GLOSSY_IN, &glossy_temporal::BLEND, Access::StorageRead));
    io.push(TargetBinding::new(GLOSSY_HISTORY, &glossy_temporal::HISTORY, Access::StorageWrite));
    if let Some(chain) = up.get(&specular::SPECULAR) {
        io.push(TargetBinding::new(SPECULAR_IN, chain, Access::StorageRead));
    }
    io.push(TargetBinding::new(REFLECTED_OUT, &REFLECTED, Access::StorageWrite));
    io
}

pub const PASS: PassDesc = PassDesc {
    name: "glossy filter",
    this_frame: super::every_frame,
    skip: glossy::skip,
    uses: |_: &ShadingConfig, up| fullscreen::uses(&io(up), false),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        let shader = match i.upstream.get(&specular::SPECULAR) {
            Some(_) => "glossy_filter_specular",
            None => "glossy_filter.comp",
        };
        FullScreen::create(i, "glossy filter", io(i.upstream), Shader::Compute(shader), &spec)
    },
};
