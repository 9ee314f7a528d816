//! Pass `tonemap`: exposure and Reinhard on luminance, sRGB-encoded into the
//! 8-bit output that is read back or presented (glsl/tonemap.comp).

use ash::vk;

use super::composite::HDR;
use super::fullscreen::{self, FullScreen, Io, Shader};
use super::{Init, PassDesc};
use crate::gpu::shared::{TONEMAP_IN, TONEMAP_OUT};
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// The displayable frame.
pub static LDR: TargetDesc = TargetDesc::new("tonemapped output", vk::Format::R8G8B8A8_UNORM);

fn io(_: &ShadingConfig) -> Vec<Io> {
    vec![Io::new(TONEMAP_IN, &HDR, Access::StorageRead), Io::new(TONEMAP_OUT, &LDR, Access::StorageWrite)]
}

pub const PASS: PassDesc = PassDesc {
    name: "tonemap",
    skip: |_| None,
    uses: |c| fullscreen::uses(&io(c), false),
    create: |i: &Init| {
        FullScreen::create(
            i,
            "tonemap",
            io(i.config),
            Shader::Compute("tonemap.comp"),
            &Specialization::new(&[]),
        )
    },
};
