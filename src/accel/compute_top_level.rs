//! GPU refit of the compute backend's top level (glsl/anim/tlas_refit.comp), right after the skinned
//! BLAS refit: the host builds topology before the frame, the GPU fills in this frame's refit roots,
//! so tracing never waits for a readback.

use anyhow::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::gpu::shared::{
    TOP_FIT_BLAS_NODES, TOP_FIT_INSTANCES, TOP_FIT_NODES, TOP_FIT_ORDER, TOP_FIT_PRIMS,
};

use super::bvh::{Bvh, MAX_DEPTH};
use crate::vk::frame_ring::Uploads;
use crate::vk::pipeline::{bind_compute, compute_pipeline, pipeline_layout, DescriptorSet, Specialization};
use crate::vk::{built, memory_barrier, Buffer, Context};

/// Rewritten through the ring slot every frame something moves (never in place: a frame in flight
/// reads them), sized once for the worst case. Host-visible only for tests (`gpu_top_level`).
pub(super) fn host_buffer(ctx: &Context, name: &str, bytes: usize) -> Result<Buffer> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
    Buffer::new(ctx, name, bytes as u64, usage, MemoryLocation::CpuToGpu)
}

/// Mirrors `Push` in glsl/anim/tlas_refit.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Levels {
    level_offset: u32,
    level_count: u32,
}

pub struct TopLevelRefit {
    /// Rewritten with each new topology, through the frame's ring slot.
    order: Buffer,
    levels: Levels,
    set: DescriptorSet,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

impl TopLevelRefit {
    /// `instances`: the most instances the top level can hold. The buffers
    /// are the compute BVH's (top-level nodes and instance order, instance
    /// records, BLAS nodes).
    pub fn new(
        ctx: &Context,
        instances: usize,
        tlas_nodes: &Buffer,
        tlas_prims: &Buffer,
        records: &Buffer,
        blas_nodes: &Buffer,
    ) -> Result<TopLevelRefit> {
        // Every node plus the level boundaries of the deepest allowed tree.
        let capacity = (2 * instances.max(1) - 1) + MAX_DEPTH + 2;
        let order = host_buffer(ctx, "BVH top-level refit order", 4 * capacity)?;
        // Objects land in `fit` as they are made: an error destroys them.
        let fit = TopLevelRefit {
            order,
            levels: Levels::default(),
            set: DescriptorSet::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        };
        built(ctx, fit, |fit| {
            fit.set = DescriptorSet::storage_buffers(
                ctx,
                "BVH top-level refit set",
                &[
                    (TOP_FIT_NODES, tlas_nodes.raw),
                    (TOP_FIT_PRIMS, tlas_prims.raw),
                    (TOP_FIT_INSTANCES, records.raw),
                    (TOP_FIT_BLAS_NODES, blas_nodes.raw),
                    (TOP_FIT_ORDER, fit.order.raw),
                ],
            )?;
            let push = std::mem::size_of::<Levels>() as u32;
            fit.layout = pipeline_layout(ctx, "BVH top-level refit layout", &[fit.set.layout], push)?;
            fit.pipeline =
                compute_pipeline(ctx, "anim/tlas_refit.comp", fit.layout, &Specialization::new(&[]))?;
            Ok(())
        })
    }

    /// Takes the level order of a new top-level topology (None: the top
    /// level holds no instance, nothing to fit), staged in the frame's slot.
    pub fn set_tree(&mut self, up: &mut Uploads, tlas: Option<&Bvh>) -> Result<()> {
        let Some(tlas) = tlas else {
            self.levels = Levels::default();
            return Ok(());
        };
        let (order, bounds) = tlas.levels();
        up.write(&self.order, 0, bytemuck::cast_slice(&order))?;
        up.write(&self.order, order.len() * 4, bytemuck::cast_slice(&bounds))?;
        self.levels = Levels { level_offset: order.len() as u32, level_count: bounds.len() as u32 - 1 };
        Ok(())
    }

    /// Records the fit (after the BLAS refit's barrier) and the barrier to
    /// the tracer (and to a host read of the nodes after the fence, for tests).
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        if self.levels.level_count == 0 {
            return;
        }
        let d = &ctx.device;
        unsafe {
            bind_compute(ctx, cmd, self.pipeline, self.layout, &[self.set.set]);
            d.cmd_push_constants(
                cmd,
                self.layout,
                vk::ShaderStageFlags::ALL,
                0,
                bytemuck::bytes_of(&self.levels),
            );
            d.cmd_dispatch(cmd, 1, 1, 1);
        }
        memory_barrier(
            ctx,
            cmd,
            (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::HOST,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::HOST_READ,
            ),
        );
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_pipeline(self.pipeline, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        self.set.destroy(ctx);
        self.order.destroy(ctx);
    }
}

crate::destroy_by_method!(TopLevelRefit);
