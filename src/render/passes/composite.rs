//! Pass `composite`: emission + direct light + ambient environment light +
//! the specular chain at the primary hit, the environment where the camera
//! ray missed (glsl/composite.comp); or, in a debug view, the G-buffer view.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{direct, gbuffer, reference, specular, terms, Creation, PassDesc};
use crate::gpu::shared::{DIRECT_IN, HDR_OUT, REFERENCE_IN, SPECULAR_IN, TERMS_IN};
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Linear radiance of the frame.
pub static HDR: TargetDesc = TargetDesc::new("hdr radiance", vk::Format::R32G32B32A32_SFLOAT);

fn io(c: &ShadingConfig) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    if !c.debug_view {
        io.push(TargetBinding::new(DIRECT_IN, &direct::DIRECT, Access::StorageRead));
    }
    if specular::skip(c).is_none() {
        io.push(TargetBinding::new(SPECULAR_IN, &specular::SPECULAR, Access::StorageRead));
    }
    if reference::skip(c).is_none() {
        io.push(TargetBinding::new(REFERENCE_IN, &reference::ACCUMULATION, Access::StorageRead));
    }
    if terms::skip(c).is_none() {
        io.push(TargetBinding::new(TERMS_IN, &terms::ACCUMULATION, Access::StorageRead));
    }
    io.push(TargetBinding::new(HDR_OUT, &HDR, Access::StorageWrite));
    io
}

fn shader(c: &ShadingConfig) -> &'static str {
    // (ShadingConfig::resolve allows terms neither beside the reference
    // nor in a debug view.)
    let (reference, terms) = (reference::skip(c).is_none(), terms::skip(c).is_none());
    match (c.debug_view, specular::skip(c).is_none(), reference, terms) {
        (true, ..) => "composite_debug",
        (false, true, true, _) => "composite_specular_reference",
        (false, true, false, true) => "composite_specular_terms",
        (false, true, false, false) => "composite_specular",
        (false, false, true, _) => "composite_reference",
        (false, false, false, true) => "composite_terms",
        (false, false, false, false) => "composite.comp",
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "composite",
    skip: |_| None,
    uses: |c| {
        // The primary hit's emission is looked up from its triangle's
        // material (no G-buffer target): the scene geometry is read, and
        // skinning may have just written it.
        let mut u = fullscreen::uses(&io(c), false);
        u.push(Use::buffer(SharedBuffer::Geometry, Access::ShaderRead));
        u
    },
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(i, "composite", io(i.config), Shader::Compute(shader(i.config)), &spec)
    },
};
