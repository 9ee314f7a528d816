//! Pass `edge aa`: geometric edge anti-aliasing after tone mapping (Shishkovtsov, GPU Gems 2 ch. 9;
//! Sabino's Eq. 4.2; glsl/aa_edge.comp). Pixels away from depth/normal discontinuities are copied.
//!
//! Depth comes from intersecting each pixel's camera ray with its stored triangle's plane, not from
//! the depth attachment: pure-RT mode has none, so both modes measure depth the same way.

use super::antialias::{self, AA_LDR};
use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::tonemap::LDR;
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::{AA_IN, AA_OUT, GB_HIT, GB_NORMAL, SPEC_EDGE_AA_TILED};
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::shading::{AaMode, ShadingConfig};
use crate::vk::pipeline::Specialization;

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    vec![
        TargetBinding::new(GB_NORMAL, &gbuffer::NORMAL, Access::Sampled),
        TargetBinding::new(GB_HIT, &gbuffer::HIT, Access::Sampled),
        TargetBinding::new(AA_IN, &LDR, Access::StorageRead),
        TargetBinding::new(AA_OUT, &AA_LDR, Access::StorageWrite),
    ]
}

fn uses(c: &ShadingConfig) -> Vec<Use> {
    let mut u = fullscreen::uses(&io(c), false);
    // The hit triangles' vertices (skinned ones written by the update).
    u.push(Use::buffer(SharedBuffer::Geometry, Access::ShaderRead));
    u
}

pub const PASS: PassDesc = PassDesc {
    name: "edge aa",
    this_frame: super::every_frame,
    skip: |c| antialias::skip(c, AaMode::Edge),
    uses: |c, _| uses(c),
    create: |i: &Creation| {
        FullScreen::create(
            i,
            "edge aa",
            io(i.config),
            Shader::Compute("aa_edge.comp"),
            &Specialization::new(&[(SPEC_EDGE_AA_TILED, i.config.edge_aa_tiled as u32)]),
        )
    },
};
