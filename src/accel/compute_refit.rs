//! GPU refit of the compute backend's skinned BVHs (glsl/anim/bvh_refit.comp), one workgroup per BVH,
//! levels deepest first. The roots feed the GPU top-level fit and come back to the host for the
//! rebuild policy and next topology.

use anyhow::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::bvh::{Bvh, BvhNode, MAX_DEPTH};
use crate::gpu::scene::{GpuScene, PrimitiveRange};
use crate::gpu::shared::{
    REFIT_INDICES, REFIT_JOBS, REFIT_NODES, REFIT_ORDER, REFIT_PRIMS, REFIT_ROOTS, REFIT_VERTICES,
};
use crate::vk::frame_ring::{upload_now, Source, Uploads};
use crate::vk::pipeline::{bind_compute, compute_pipeline, pipeline_layout, DescriptorSet, Specialization};
use crate::vk::{built, memory_barrier, Buffer, Context};

/// Mirrors `RefitJob` in glsl/anim/bvh_refit.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RefitJob {
    pub node_offset: u32,
    pub prim_offset: u32,
    pub first_index: u32,
    pub vertex_offset: u32,
    pub order_offset: u32,
    pub level_offset: u32,
    pub level_count: u32,
    pub pad: u32,
}

pub struct ComputeRefit {
    jobs: Buffer,
    order: Buffer,
    roots: Buffer,
    job_list: Vec<RefitJob>,
    set: DescriptorSet,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

/// `order` entries a tree over `triangles` can need: every node plus the
/// level boundaries of the deepest allowed tree.
fn order_capacity(triangles: u32) -> u32 {
    (2 * triangles).saturating_sub(1) + MAX_DEPTH as u32 + 2
}

impl ComputeRefit {
    /// `bvhs`: per skinned slot, its BVH and where its nodes / triangle
    /// order live in the shared node / prim buffers.
    pub fn new(
        ctx: &Context,
        gpu: &GpuScene,
        bvhs: &[(&Bvh, u32, u32)],
        nodes: &Buffer,
        prims: &Buffer,
    ) -> Result<ComputeRefit> {
        let mut job_list = Vec::new();
        let mut order_len = 0u32;
        for (&(_, node_offset, prim_offset), r) in bvhs.iter().zip(&gpu.skinned) {
            let r: &PrimitiveRange = r;
            job_list.push(RefitJob {
                node_offset,
                prim_offset,
                first_index: r.first_index,
                vertex_offset: r.vertex_offset,
                order_offset: order_len,
                ..Default::default()
            });
            order_len += order_capacity(r.index_count / 3);
        }
        // Objects land in `refit` as they are made: an error destroys them.
        let refit = ComputeRefit {
            jobs: Buffer::null(),
            order: Buffer::null(),
            roots: Buffer::null(),
            job_list,
            set: DescriptorSet::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        };
        built(ctx, refit, |refit| {
            refit.create(ctx, gpu, nodes, prims, order_len)?;
            upload_now(ctx, "BVH refit levels", |up| {
                for (slot, (bvh, _, _)) in bvhs.iter().enumerate() {
                    refit.set_levels(up, slot, bvh)?;
                }
                Ok(())
            })
        })
    }

    fn create(
        &mut self,
        ctx: &Context,
        gpu: &GpuScene,
        nodes: &Buffer,
        prims: &Buffer,
        order_len: u32,
    ) -> Result<()> {
        // Written through the frame ring, read through its downloads.
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let (src, dst) = (vk::BufferUsageFlags::TRANSFER_SRC, vk::BufferUsageFlags::TRANSFER_DST);
        let buffer =
            |name: &str, bytes: u64, usage| Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly);
        let jobs = self.job_list.len();
        self.jobs = buffer("BVH refit jobs", (jobs * 32) as u64, storage | dst)?;
        self.order = buffer("BVH refit level order", order_len as u64 * 4, storage | dst)?;
        let roots_size = (jobs * std::mem::size_of::<BvhNode>()) as u64;
        self.roots = buffer("BVH refit roots", roots_size, storage | src)?;
        self.set = DescriptorSet::storage_buffers(
            ctx,
            "BVH refit set",
            &[
                (REFIT_NODES, nodes.raw),
                (REFIT_PRIMS, prims.raw),
                (REFIT_VERTICES, gpu.vertices.raw),
                (REFIT_INDICES, gpu.indices.raw),
                (REFIT_JOBS, self.jobs.raw),
                (REFIT_ORDER, self.order.raw),
                (REFIT_ROOTS, self.roots.raw),
            ],
        )?;
        self.layout = pipeline_layout(ctx, "BVH refit layout", &[self.set.layout], 0)?;
        self.pipeline = compute_pipeline(ctx, "anim/bvh_refit.comp", self.layout, &Specialization::new(&[]))?;
        Ok(())
    }

    /// Writes the level order of `slot`'s (new) tree (through the frame's
    /// ring slot).
    pub fn set_levels(&mut self, up: &mut Uploads, slot: usize, bvh: &Bvh) -> Result<()> {
        let (order, bounds) = bvh.levels();
        let job = &mut self.job_list[slot];
        job.level_offset = job.order_offset + order.len() as u32;
        job.level_count = bounds.len() as u32 - 1;
        up.write(&self.order, job.order_offset as usize * 4, bytemuck::cast_slice(&order))?;
        up.write(&self.order, job.level_offset as usize * 4, bytemuck::cast_slice(&bounds))?;
        up.write(&self.jobs, slot * 32, bytemuck::bytes_of(job))
    }

    /// Records the refit of every skinned BVH (after the skinning barrier)
    /// and the barrier to the tracer (the ring's download at the frame's
    /// end waits for the roots itself).
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        let d = &ctx.device;
        unsafe {
            bind_compute(ctx, cmd, self.pipeline, self.layout, &[self.set.set]);
            d.cmd_dispatch(cmd, self.job_list.len() as u32, 1, 1);
        }
        memory_barrier(
            ctx,
            cmd,
            (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
            (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_READ),
        );
    }

    /// Where the ring's download reads the refit roots from.
    pub fn roots_source(&self) -> Source {
        let size = (self.job_list.len() * std::mem::size_of::<BvhNode>()) as u64;
        Source::Buffer { buffer: self.roots.raw, offset: 0, size }
    }

    /// Root nodes by slot, from the bytes of `roots_source` of a completed frame.
    pub fn roots(&self, bytes: &[u8]) -> Vec<BvhNode> {
        bytemuck::pod_collect_to_vec(bytes)
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_pipeline(self.pipeline, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        self.set.destroy(ctx);
        for b in [&mut self.jobs, &mut self.order, &mut self.roots] {
            b.destroy(ctx);
        }
    }
}

crate::destroy_by_method!(ComputeRefit);
