//! Pass `tonemap`: exposure (fixed, or adapted by the `luminance` pass),
//! the tone curve (render/tone.rs), sRGB-encoded into the 8-bit output that
//! is read back or presented (glsl/tonemap.comp). Counts NaN/Inf pixels.

use ash::vk;

use super::composite::HDR;
use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{Creation, PassDesc};
use crate::gpu::shared::{TONEMAP_IN, TONEMAP_OUT};
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// The displayable frame.
pub static LDR: TargetDesc = TargetDesc::new("tonemapped output", vk::Format::R8G8B8A8_UNORM);

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    vec![
        TargetBinding::new(TONEMAP_IN, &HDR, Access::StorageRead),
        TargetBinding::new(TONEMAP_OUT, &LDR, Access::StorageWrite),
    ]
}

pub const PASS: PassDesc = PassDesc {
    name: "tonemap",
    this_frame: super::every_frame,
    skip: |_| None,
    uses: |c, _| {
        let mut u = fullscreen::uses(&io(c), false);
        // The bad-pixel counter; the measured exposure when there is one.
        u.push(Use::buffer(SharedBuffer::Counters, Access::ShaderWrite));
        if c.luminance {
            u.push(Use::buffer(SharedBuffer::Exposure, Access::ShaderRead));
        }
        u
    },
    create: |i: &Creation| {
        FullScreen::create(
            i,
            "tonemap",
            io(i.config),
            Shader::Compute("tonemap.comp"),
            &Specialization::new(&[]),
        )
    },
};

/// The SPIR-V reflection (vk/reflect.rs) on this pass's shader: it lives
/// here, not in `vk`, because the bindings it expects are the pass's.
#[cfg(test)]
mod tests {
    use ash::vk;

    use crate::gpu::shared::{SET_PASS, TONEMAP_IN, TONEMAP_OUT};
    use crate::vk::reflect::{spirv_image_format, storage_image_formats};

    #[test]
    fn finds_the_tone_mapper_s_image_formats() {
        let words = crate::vk::pipeline::spirv("tonemap.comp").unwrap();
        let f = storage_image_formats(&words);
        let rgba32f = spirv_image_format(vk::Format::R32G32B32A32_SFLOAT).unwrap();
        let rgba8 = spirv_image_format(vk::Format::R8G8B8A8_UNORM).unwrap();
        assert_eq!(f, vec![(SET_PASS, TONEMAP_IN, rgba32f), (SET_PASS, TONEMAP_OUT, rgba8)]);
    }
}
