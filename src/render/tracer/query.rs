//! Ray-query tracing (VK_KHR_ray_query): the passes are compute shaders
//! that traverse the TLAS with `rayQueryEXT` (glsl/trace/query.glsl).

use anyhow::Result;
use ash::vk;

use crate::render::kernel::Kernel;
use crate::vk::pipeline::Specialization;
use crate::vk::Context;

pub fn kernel(
    ctx: &Context,
    pass: &str,
    layout: vk::PipelineLayout,
    spec: &Specialization,
) -> Result<Kernel> {
    Kernel::compute(ctx, &format!("{pass}_query"), layout, spec)
}
