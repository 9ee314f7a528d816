//! Ray-tracing-pipeline tracing (VK_KHR_ray_tracing_pipeline): each pass is
//! a ray-generation shader plus the shared miss and hit shaders, which only
//! report hits (glsl/rt/); the shader binding table is built from them.

use anyhow::Result;
use ash::vk;

use crate::gpu::shared::{HIT_GROUP_SHADOW, HIT_GROUP_STRIDE, HIT_GROUP_VISIBLE};
use crate::render::kernel::Kernel;
use crate::vk::pipeline::Specialization;
use crate::vk::rt_pipeline::{RtPipeline, RtShaders};
use crate::vk::Context;

/// Hit groups in SBT order (HIT_GROUP_VISIBLE, HIT_GROUP_SHADOW): visibility
/// rays report the closest hit after alpha-mask any-hits; shadow rays only
/// run any-hits (transmittance, cut-outs).
const HIT_GROUPS: [(Option<&str>, Option<&str>); HIT_GROUP_STRIDE as usize] =
    [(Some("rt/closest.rchit"), Some("rt/visible.rahit")), (None, Some("rt/shadow.rahit"))];
const _: () = assert!(HIT_GROUP_VISIBLE == 0 && HIT_GROUP_SHADOW == 1);

pub fn kernel(
    ctx: &Context,
    pass: &str,
    layout: vk::PipelineLayout,
    spec: &Specialization,
) -> Result<Kernel> {
    let raygen = format!("{pass}.rgen");
    let shaders = RtShaders { raygen: &raygen, miss: &["rt/miss.rmiss"], hit_groups: &HIT_GROUPS };
    Ok(Kernel::RayTracing(RtPipeline::new(ctx, &shaders, layout, spec)?))
}
