//! Pass `fxaa`: luminance edge AA after tone mapping, after FXAA 3.11's quality preset (Lottes 2011;
//! glsl/aa_fxaa.comp). Needing no G-buffer, it also smooths edges the geometric filter cannot see
//! (textures, shadow boundaries, reflections).

use super::antialias::{self, AA_LDR};
use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::tonemap::LDR;
use super::{Creation, PassDesc};
use crate::gpu::shared::{AA_IN, AA_OUT};
use crate::render::frame::Access;
use crate::render::shading::{AaMode, ShadingConfig};
use crate::vk::pipeline::Specialization;

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    vec![
        TargetBinding::new(AA_IN, &LDR, Access::StorageRead),
        TargetBinding::new(AA_OUT, &AA_LDR, Access::StorageWrite),
    ]
}

pub const PASS: PassDesc = PassDesc {
    name: "fxaa",
    this_frame: super::every_frame,
    skip: |c| antialias::skip(c, AaMode::Fxaa),
    uses: |c, _| fullscreen::uses(&io(c), false),
    create: |i: &Creation| {
        FullScreen::create(
            i,
            "fxaa",
            io(i.config),
            Shader::Compute("aa_fxaa.comp"),
            &Specialization::new(&[]),
        )
    },
};
