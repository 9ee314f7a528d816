//! Pass `ao`: the diffuse ambient at the primary hit from traced rays (`--ambient traced`,
//! glsl/passes/ao.glsl): AO_SAMPLES cosine rays a pixel, unlimited in range; the share of the
//! environment's light they find unoccluded (each weighted by the smoothed environment along it) and,
//! unless `--no-indirect`, the irradiance their hits bounce (direct and environment light, shadow rays
//! traced), and the emissive triangles' direct light (light samples MIS-weighted against the rays that
//! hit them; on the diffuse lobe and on a specular lobe no glossy ray samples), which `ao filter`
//! denoises. Left out where nothing lights the scene or nothing occludes,
//! beside the ray-traced reference (which replaces the ambient) and in debug views. The per-object budget does not govern it: its rays are part
//! of the frame's fixed cost, like the raster passes.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{gbuffer, Creation, PassDesc};
use crate::gpu::shared::{AO_BOUNCE_OUT, AO_GRID, AO_OUT, AO_SAMPLES, AO_SPECULAR_OUT};
use crate::render::frame::Access;
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

// The 16 pixels of a 4x4 tile fill the AO_GRID² cells of one stratified grid (glsl/passes/ao.glsl).
const _: () = assert!(AO_GRID * AO_GRID == 16 * AO_SAMPLES);

/// Per pixel the visible share of the ambient (rgb) and the camera distance (a; 0: no sample).
pub static SAMPLE: TargetDesc = TargetDesc::new("ambient visibility sample", vk::Format::R32G32B32A32_SFLOAT);
/// Per pixel the irradiance the rays' hits bounce and the emitters send (rgb).
pub static BOUNCE: TargetDesc = TargetDesc::new("ambient bounce sample", vk::Format::R32G32B32A32_SFLOAT);
/// Per pixel the emitters' light on a specular lobe no glossy ray samples, over the lobe's albedo (rgb).
pub static SPECULAR: TargetDesc = TargetDesc::new("emitter specular sample", vk::Format::R32G32B32A32_SFLOAT);

/// `emitter specular sample` exists where the scene emits (ShadingConfig::ao_emitter_specular).
fn io(c: &ShadingConfig) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    io.push(TargetBinding::new(AO_OUT, &SAMPLE, Access::StorageWrite));
    io.push(TargetBinding::new(AO_BOUNCE_OUT, &BOUNCE, Access::StorageWrite));
    if c.ao_emitter_specular {
        io.push(TargetBinding::new(AO_SPECULAR_OUT, &SPECULAR, Access::StorageWrite));
    }
    io
}

pub fn skip(c: &ShadingConfig) -> Option<&'static str> {
    if c.ambient_visibility {
        None
    } else if c.debug_view {
        Some("a debug view shows the G-buffer instead")
    } else if c.reference {
        Some("the ray-traced reference replaces the ambient")
    } else if !c.needs.ambient_occluders {
        Some("no light to shadow or bounce, or nothing to occlude it")
    } else {
        Some("--ambient is not traced")
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "ao",
    this_frame: super::every_frame,
    skip,
    uses: |c, _| fullscreen::uses(&io(c), true),
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        let shader = if i.config.ao_emitter_specular { "ao_emitters" } else { "ao" };
        FullScreen::create(i, "ao", io(i.config), Shader::Traced(shader), &spec)
    },
};
