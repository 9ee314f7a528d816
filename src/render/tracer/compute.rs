//! Our own BVH traversed in compute shaders (glsl/trace/compute.glsl): no ray-tracing extension
//! needed. Skinned trees and then the top level are refit on the GPU (topology built by the host
//! before the frame), so updates need no host step inside the frame.

use anyhow::Result;
use ash::vk;

use super::hardware::counts;
use super::{Tracer, UpdateCounts};
use crate::accel::compute_bvh::ComputeBvh;
use crate::accel::dynamic::{RebuildPolicy, Update};
use crate::gpu::GpuScene;
use crate::render::frame::{Access, Recorder, SharedBuffer, Use};
use crate::render::kernel::Kernel;
use crate::render::shading::Backend;
use crate::scene::{Aabb, Scene};
use crate::vk::frame_ring::{Source, Uploads};
use crate::vk::pipeline::{DescriptorSet, Specialization};
use crate::vk::Context;

pub struct ComputeTracer {
    bvh: ComputeBvh,
}

impl ComputeTracer {
    pub fn new(ctx: &Context, scene: &Scene, gpu: &GpuScene) -> Result<ComputeTracer> {
        if !ctx.caps.subgroup_ops {
            anyhow::bail!(
                "device {} lacks subgroup ballot operations in compute shaders, which the \
                 compute tracer's packet traversal needs (use --backend query or pipeline)",
                ctx.caps.name
            );
        }
        Ok(ComputeTracer { bvh: ComputeBvh::build(ctx, scene, gpu)? })
    }
}

impl Tracer for ComputeTracer {
    fn backend(&self) -> Backend {
        Backend::Compute
    }

    fn accel_stats(&self) -> super::AccelStats {
        super::AccelStats { build_ms: self.bvh.build_ms, bytes: self.bvh.bytes() }
    }

    fn kernel(
        &self,
        ctx: &Context,
        pass: &str,
        layout: vk::PipelineLayout,
        spec: &Specialization,
    ) -> Result<Kernel> {
        Kernel::compute(ctx, &format!("{pass}_compute"), layout, spec)
    }

    fn set(&self) -> &DescriptorSet {
        &self.bvh.set
    }

    fn prepare_update(
        &mut self,
        up: &mut Uploads,
        scene: &Scene,
        _: &GpuScene,
        policy: &RebuildPolicy,
    ) -> Result<Vec<Update>> {
        self.bvh.prepare_update(up, scene, policy)
    }

    fn record_update(&mut self, rec: &mut Recorder, _: &Scene, _: &GpuScene) -> Result<()> {
        if self.bvh.skinned_count() == 0 {
            // Rigid motion only: the host's top level is exact.
            return Ok(());
        }
        let (ctx, bvh) = (rec.ctx, &self.bvh);
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let refit = [
            Use::buffer(SharedBuffer::Geometry, Access::ShaderRead),
            Use::buffer(SharedBuffer::Accel, Access::ShaderWrite),
        ];
        rec.pass("bvh refit", compute, &refit, |cmd| {
            bvh.record_refit(ctx, cmd);
            Ok(())
        })?;
        rec.pass("top level fit", compute, &[Use::buffer(SharedBuffer::Accel, Access::ShaderWrite)], |cmd| {
            bvh.record_top_level(ctx, cmd);
            Ok(())
        })
    }

    fn readback(&self) -> Option<Source> {
        self.bvh.roots_source()
    }

    fn finish_update(
        &mut self,
        plan: &[Update],
        _: &[Aabb],
        roots: Option<&[u8]>,
        policy: &RebuildPolicy,
    ) -> Result<(UpdateCounts, Vec<(&'static str, f64)>)> {
        self.bvh.finish_update(plan, policy, roots)?;
        let mut times = vec![("top level (CPU)", self.bvh.top_level_ms)];
        if plan.contains(&Update::Rebuild) {
            times.insert(0, ("bvh rebuild (CPU)", self.bvh.rebuild_ms));
        }
        Ok((counts(plan), times))
    }

    fn destroy(&mut self, ctx: &Context) {
        self.bvh.destroy(ctx);
    }
}
