//! Pass `path` (`--mode path`): the path-traced ground truth (glsl/path/path.glsl), adding
//! PATH_SAMPLES_PER_FRAME paths per pixel a frame to its accumulation and writing the mean into the HDR
//! target `luminance` and `tonemap` read. The only shading pass of `PATH_FRAME`; render/path.rs
//! drives the frames.

use ash::vk;

use super::composite::HDR;
use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{Creation, PassDesc};
use crate::gpu::shared::{PATH_ACCUM, PATH_OUT};
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::shading::{Mode, ShadingConfig};
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Per pixel the sum of the paths' radiance (rgb) and their count (a),
/// kept from frame to frame.
pub static ACCUMULATION: TargetDesc = TargetDesc::kept("path accumulation", vk::Format::R32G32B32A32_SFLOAT);

fn io(_: &ShadingConfig) -> Vec<TargetBinding> {
    vec![
        TargetBinding::new(PATH_ACCUM, &ACCUMULATION, Access::StorageWrite),
        TargetBinding::new(PATH_OUT, &HDR, Access::StorageWrite),
    ]
}

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    (c.mode != Mode::Path).then_some("not --mode path")
}

pub const PASS: PassDesc = PassDesc {
    name: "path",
    this_frame: super::every_frame,
    skip,
    uses: |c, _| {
        let mut u = fullscreen::accumulating_uses(&io(c), &ACCUMULATION);
        u.push(Use::buffer(SharedBuffer::Counters, Access::ShaderWrite));
        u
    },
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        FullScreen::create(i, "path", io(i.config), Shader::Traced("path"), &spec)
    },
};
