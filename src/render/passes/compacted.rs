//! Compaction for a full-screen tracing pass with sparse work (e.g. `specular`: mirrors and glass): a
//! select kernel lists the pixels that need the traced kernel, which then runs once per listed pixel,
//! launched indirectly (glsl/common/work_list.glsl). Why: a SIMD vector or warp runs at the speed of
//! its busiest lane; on llvmpipe the full-screen specular loop ran at 21 % lane occupancy on Sponza
//! with spheres (bench/results/lavapipe-2core-vm-frame-passes.md, with gains and costs).
//!
//! Header and barriers are private to the pass; the list is a target (`LIST`) so it follows the
//! frame size and exists only where such a pass runs.

use anyhow::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;
use vk::AccessFlags2 as A;
use vk::PipelineStageFlags2 as S;

use super::fullscreen::TargetBinding;
use crate::gpu::shared::{WORK_COUNT, WORK_GROUPS_X, WORK_HEADER, WORK_HEADER_WORDS, WORK_LIST};
use crate::render::frame::Access;
use crate::render::kernel::Kernel;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::{bind_compute, compute_pipeline, DescriptorSet, Specialization};
use crate::vk::{built, memory_barrier, Buffer, Context};

/// The listed pixels, packed x | y << 16, read as a linear array.
pub static LIST: TargetDesc = TargetDesc::new("work list", vk::Format::R32_UINT);

/// The list's set-1 binding (written by the select kernel, read by the
/// traced one inside the pass).
pub fn list_io() -> TargetBinding {
    TargetBinding::new(WORK_LIST, &LIST, Access::StorageWrite)
}

/// The header's contents at the start of a frame: no entry, no workgroup,
/// and the 1s of both indirect commands' other dimensions.
fn header_reset() -> [u32; WORK_HEADER_WORDS as usize] {
    let mut h = [0; WORK_HEADER_WORDS as usize];
    for base in [WORK_GROUPS_X, WORK_COUNT] {
        h[base as usize + 1] = 1;
        h[base as usize + 2] = 1;
    }
    h
}

pub struct WorkList {
    select: vk::Pipeline,
    header: Buffer,
}

impl WorkList {
    /// The select kernel (`select`, a compute shader on the pass's layout)
    /// and the header, bound at WORK_HEADER in `set`.
    pub fn create(
        ctx: &Context,
        name: &str,
        select: &str,
        layout: vk::PipelineLayout,
        spec: &Specialization,
        set: &DescriptorSet,
    ) -> Result<WorkList> {
        // A device address only where the ray-generation launch reads it.
        let mut usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::INDIRECT_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST;
        if ctx.caps.trace_rays_indirect && ctx.rt_pipeline.is_some() {
            usage |= vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        }
        let size = 4 * u64::from(WORK_HEADER_WORDS);
        let header = Buffer::new(ctx, &format!("{name} work header"), size, usage, MemoryLocation::GpuOnly)?;
        let work = WorkList { select: vk::Pipeline::null(), header };
        let work = built(ctx, work, |w| {
            w.select = compute_pipeline(ctx, select, layout, spec)?;
            Ok(())
        })?;
        set.write_buffer(ctx, WORK_HEADER, work.header.raw);
        Ok(work)
    }

    /// Records reset, select and the listed launch of `kernel` with the
    /// barriers between them.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        kernel: &Kernel,
        layout: vk::PipelineLayout,
        sets: &[vk::DescriptorSet],
        extent: vk::Extent2D,
    ) {
        let traced = kernel.stage();
        // The previous frame's launch is done reading the header.
        memory_barrier(
            ctx,
            cmd,
            (S::DRAW_INDIRECT | S::COMPUTE_SHADER | traced, A::NONE),
            (S::ALL_TRANSFER, A::TRANSFER_WRITE),
        );
        unsafe {
            ctx.device.cmd_update_buffer(cmd, self.header.raw, 0, bytemuck::cast_slice(&header_reset()));
        }
        let rw = A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE;
        memory_barrier(ctx, cmd, (S::ALL_TRANSFER, A::TRANSFER_WRITE), (S::COMPUTE_SHADER, rw));
        ctx.begin_label(cmd, "select", [0.4, 0.7, 0.9, 1.0]);
        bind_compute(ctx, cmd, self.select, layout, sets);
        unsafe { ctx.device.cmd_dispatch(cmd, extent.width.div_ceil(8), extent.height.div_ceil(8), 1) };
        ctx.end_label(cmd);
        // The list and header to the launch; the select kernel's image writes (pixels the listed kernel
        // does not touch) too.
        memory_barrier(
            ctx,
            cmd,
            (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE),
            (S::DRAW_INDIRECT | traced, A::INDIRECT_COMMAND_READ | rw),
        );
        ctx.begin_label(cmd, "listed pixels", [0.9, 0.7, 0.4, 1.0]);
        kernel.dispatch_indirect(ctx, cmd, layout, sets, &self.header, extent);
        ctx.end_label(cmd);
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe { ctx.device.destroy_pipeline(self.select, None) };
        self.header.destroy(ctx);
    }
}

crate::destroy_by_method!(WorkList);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reset_header_is_two_empty_indirect_commands() {
        let h = header_reset();
        let at = |base: u32| &h[base as usize..base as usize + 3];
        assert_eq!(at(WORK_GROUPS_X), [0, 1, 1], "VkDispatchIndirectCommand");
        assert_eq!(at(WORK_COUNT), [0, 1, 1], "VkTraceRaysIndirectCommandKHR");
    }
}
