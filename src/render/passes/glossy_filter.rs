//! Pass `glossy filter`: the glossy correction (`glossy temporal`'s blend, or without temporal reuse the
//! frame's sample) denoised by a joint bilateral filter guided by the G-buffer and scaled by the lobe's
//! albedo, the blend kept as the next frame's history (temporal reuse only), plus the specular chain
//! where `specular` runs
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

fn io(c: &ShadingConfig, up: &Upstream) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    if c.glossy_temporal {
        io.push(TargetBinding::new(GLOSSY_IN, &glossy_temporal::BLEND, Access::StorageRead));
        io.push(TargetBinding::new(GLOSSY_HISTORY, &glossy_temporal::HISTORY, Access::StorageWrite));
    } else {
        io.push(TargetBinding::new(GLOSSY_IN, &glossy::GLOSSY, Access::StorageRead));
    }
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
    uses: |c: &ShadingConfig, up| fullscreen::uses(&io(c, up), false),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        let shader = match (i.upstream.get(&specular::SPECULAR).is_some(), i.config.glossy_temporal) {
            (true, true) => "glossy_filter_specular_temporal",
            (true, false) => "glossy_filter_specular",
            (false, true) => "glossy_filter_temporal",
            (false, false) => "glossy_filter.comp",
        };
        FullScreen::create(i, "glossy filter", io(i.config, i.upstream), Shader::Compute(shader), &spec)
    },
};
