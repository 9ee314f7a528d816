//! Pass `ao filter`: `ao`'s per-pixel visible share and bounce denoised by a joint bilateral filter guided
//! by the G-buffer's normals and hit distances and combined with the SH irradiance (glsl/ao_filter.comp)
//! into the diffuse ambient `composite` shades with; the emitters' specular light, where the scene
//! emits, is averaged alike.
//! Runs exactly when `ao` does.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{ao, gbuffer, Creation, PassDesc};
use crate::gpu::shared::{AO_BOUNCE_IN, AO_EMITTER_SPECULAR_OUT, AO_IN, AO_SPECULAR_IN, AO_VISIBILITY_OUT};
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// The traced diffuse ambient radiance (rgb: what a white Lambertian surface exits) and the mean visible
/// share (a).
pub static VISIBILITY: TargetDesc = TargetDesc::new("ambient visibility", vk::Format::R32G32B32A32_SFLOAT);
/// The emitters' light on a specular lobe no glossy ray samples, over the lobe's albedo (rgb).
pub static EMITTER_SPECULAR: TargetDesc =
    TargetDesc::new("emitter specular", vk::Format::R32G32B32A32_SFLOAT);

fn io(c: &ShadingConfig) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    io.push(TargetBinding::new(AO_IN, &ao::SAMPLE, Access::StorageRead));
    io.push(TargetBinding::new(AO_BOUNCE_IN, &ao::BOUNCE, Access::StorageRead));
    io.push(TargetBinding::new(AO_VISIBILITY_OUT, &VISIBILITY, Access::StorageWrite));
    if c.ao_emitter_specular {
        io.push(TargetBinding::new(AO_SPECULAR_IN, &ao::SPECULAR, Access::StorageRead));
        io.push(TargetBinding::new(AO_EMITTER_SPECULAR_OUT, &EMITTER_SPECULAR, Access::StorageWrite));
    }
    io
}

pub const PASS: PassDesc = PassDesc {
    name: "ao filter",
    this_frame: super::every_frame,
    skip: ao::skip,
    uses: |c, _| fullscreen::uses(&io(c), false),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        let shader = if i.config.ao_emitter_specular { "ao_filter_emitters" } else { "ao_filter.comp" };
        FullScreen::create(i, "ao filter", io(i.config), Shader::Compute(shader), &spec)
    },
};
