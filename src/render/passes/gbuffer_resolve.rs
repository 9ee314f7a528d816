//! Pass `gbuffer_resolve` (hybrid mode): fills the material targets from each pixel's stored triangle,
//! as the raster's fragment stage would have (glsl/gbuffer_resolve.comp): material work once per pixel
//! and no per-triangle interpolation, which was llvmpipe's G-buffer time
//! (bench/results/lavapipe-2core-vm-raster.md).

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::{GB_ALBEDO, GB_HIT, GB_MATERIAL, GB_NORMAL};
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::settings::PrimaryVisibility;
use crate::render::shading::{Mode, ShadingConfig};
use crate::vk::pipeline::Specialization;

fn io() -> Vec<TargetBinding> {
    let w = Access::StorageWrite;
    vec![
        TargetBinding::new(GB_HIT, &gbuffer::HIT, Access::StorageRead),
        TargetBinding::new(GB_ALBEDO, &gbuffer::ALBEDO, w),
        TargetBinding::new(GB_NORMAL, &gbuffer::NORMAL, w),
        TargetBinding::new(GB_MATERIAL, &gbuffer::MATERIAL, w),
    ]
}

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    match (c.mode, c.visibility) {
        (Mode::Rt, _) => Some("pure ray-traced mode: pass primary writes the whole G-buffer"),
        (_, PrimaryVisibility::Traced) => {
            Some("--primary-visibility traced: pass visibility trace resolves its hits")
        }
        _ => None,
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "gbuffer resolve",
    // The traced pass resolves its own hits.
    this_frame: |f| {
        (f.visibility == Some(super::Technique::Traced)).then_some("traced visibility this frame")
    },
    skip,
    uses: |_, _| {
        // The triangle's vertices are read (skinning may have just written them).
        let mut u = fullscreen::uses(&io(), false);
        u.push(Use::buffer(SharedBuffer::Geometry, Access::ShaderRead));
        u
    },
    create: |i: &Creation| {
        let spec = Specialization::new(&[]);
        FullScreen::create(i, "gbuffer resolve", io(), Shader::Compute("gbuffer_resolve.comp"), &spec)
    },
};
