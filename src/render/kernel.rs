//! The pipeline of a full-screen pass: a compute shader (8x8 workgroups, one invocation per pixel) or a
//! ray-tracing pipeline launched one ray-generation invocation per pixel. Passes hold one without
//! knowing which: the tracer picks it (render/tracer).

use anyhow::Result;
use ash::vk;

use crate::gpu::shared::{WORK_COUNT, WORK_GROUPS_X};
use crate::vk::memory::Buffer;
use crate::vk::pipeline::{compute_pipeline, Specialization};
use crate::vk::rt_pipeline::RtPipeline;
use crate::vk::Context;

pub enum Kernel {
    Compute(vk::Pipeline),
    RayTracing(RtPipeline),
}

impl Kernel {
    pub fn compute(
        ctx: &Context,
        shader: &str,
        layout: vk::PipelineLayout,
        spec: &Specialization,
    ) -> Result<Kernel> {
        Ok(Kernel::Compute(compute_pipeline(ctx, shader, layout, spec)?))
    }

    /// The shader stage its descriptor accesses happen in (for barriers).
    pub fn stage(&self) -> vk::PipelineStageFlags2 {
        match self {
            Kernel::Compute(_) => vk::PipelineStageFlags2::COMPUTE_SHADER,
            Kernel::RayTracing(_) => vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR,
        }
    }

    pub fn bind_point(&self) -> vk::PipelineBindPoint {
        match self {
            Kernel::Compute(_) => vk::PipelineBindPoint::COMPUTE,
            Kernel::RayTracing(_) => vk::PipelineBindPoint::RAY_TRACING_KHR,
        }
    }

    pub fn pipeline(&self) -> vk::Pipeline {
        match self {
            Kernel::Compute(p) => *p,
            Kernel::RayTracing(rt) => rt.pipeline,
        }
    }

    /// Binds the pipeline and `sets` (from set 0).
    fn bind(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        layout: vk::PipelineLayout,
        sets: &[vk::DescriptorSet],
    ) {
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, self.bind_point(), self.pipeline());
            ctx.device.cmd_bind_descriptor_sets(cmd, self.bind_point(), layout, 0, sets, &[]);
        }
    }

    /// Binds the pipeline and `sets` (from set 0) and covers `extent`: a compute kernel's workgroup
    /// covers `group` pixels (8x8 for one invocation per pixel), a ray-generation launch one per pixel.
    pub fn dispatch(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        layout: vk::PipelineLayout,
        sets: &[vk::DescriptorSet],
        extent: vk::Extent2D,
        group: [u32; 2],
    ) {
        self.bind(ctx, cmd, layout, sets);
        let d = &ctx.device;
        unsafe {
            match self {
                Kernel::Compute(_) => {
                    d.cmd_dispatch(cmd, extent.width.div_ceil(group[0]), extent.height.div_ceil(group[1]), 1)
                }
                Kernel::RayTracing(rt) => rt.trace(ctx, cmd, extent.width, extent.height),
            }
        }
    }

    /// Binds like `dispatch` and runs the invocations `work`'s header asks for
    /// (glsl/common/work_list.glsl): WORK_GROUP_SIZE-wide workgroups, or a (count, 1, 1) ray-generation
    /// launch; without indirect launches on the device, one per pixel of `extent` (spares find no entry).
    pub fn dispatch_indirect(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        layout: vk::PipelineLayout,
        sets: &[vk::DescriptorSet],
        work: &Buffer,
        extent: vk::Extent2D,
    ) {
        self.bind(ctx, cmd, layout, sets);
        let d = &ctx.device;
        unsafe {
            match self {
                Kernel::Compute(_) => d.cmd_dispatch_indirect(cmd, work.raw, 4 * u64::from(WORK_GROUPS_X)),
                Kernel::RayTracing(rt) if work.address != 0 => {
                    rt.trace_indirect(ctx, cmd, work.address + 4 * u64::from(WORK_COUNT))
                }
                Kernel::RayTracing(rt) => rt.trace(ctx, cmd, extent.width, extent.height),
            }
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        match self {
            Kernel::Compute(p) => unsafe { ctx.device.destroy_pipeline(*p, None) },
            Kernel::RayTracing(rt) => rt.destroy(ctx),
        }
    }
}
