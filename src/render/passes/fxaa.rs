//! Pass `fxaa`: luminance edge anti-aliasing after tone mapping in the
//! style of FXAA 3.11's quality preset (Lottes 2011), written for this
//! renderer (glsl/aa_fxaa.comp). It needs no G-buffer, so it also smooths
//! edges inside textures and shading (shadow boundaries, reflections) that
//! the geometric edge filter cannot see; pixels below its local contrast
//! threshold are copied unchanged.

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
