//! Our own BVH traversed in compute shaders (glsl/trace/compute.glsl): no
//! ray-tracing extension needed. Skinned trees are refit on the GPU after
//! skinning; the top level follows the instances.

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
use crate::vk::pipeline::{DescriptorSet, Specialization};
use crate::vk::Context;

pub struct ComputeTracer {
    bvh: ComputeBvh,
    plan: Vec<Update>,
    cpu_rebuild_ms: f64,
}

impl ComputeTracer {
    pub fn new(ctx: &Context, scene: &Scene, gpu: &GpuScene) -> Result<ComputeTracer> {
        Ok(ComputeTracer { bvh: ComputeBvh::build(ctx, scene, gpu)?, plan: Vec::new(), cpu_rebuild_ms: 0.0 })
    }
}

impl Tracer for ComputeTracer {
    fn backend(&self) -> Backend {
        Backend::Compute
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
        ctx: &Context,
        scene: &Scene,
        _: &GpuScene,
        policy: &RebuildPolicy,
    ) -> Result<()> {
        let t0 = std::time::Instant::now();
        self.plan = self.bvh.prepare_skinned(ctx, scene, policy)?;
        self.cpu_rebuild_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    fn record_update(&mut self, rec: &mut Recorder, _: &Scene, _: &GpuScene) -> Result<()> {
        if self.bvh.skinned_count() == 0 {
            return Ok(());
        }
        let uses = [
            Use::buffer(SharedBuffer::Geometry, Access::ShaderRead),
            Use::buffer(SharedBuffer::Accel, Access::ShaderWrite),
        ];
        let (ctx, bvh) = (rec.ctx, &self.bvh);
        rec.pass("bvh refit", vk::PipelineStageFlags2::COMPUTE_SHADER, &uses, |cmd| {
            bvh.record_refit(ctx, cmd);
            Ok(())
        })
    }

    fn finish_update(
        &mut self,
        _: &Context,
        scene: &Scene,
        _: &[Aabb],
        policy: &RebuildPolicy,
    ) -> Result<(UpdateCounts, Vec<(&'static str, f64)>)> {
        let plan = std::mem::take(&mut self.plan);
        let t0 = std::time::Instant::now();
        self.bvh.finish_refit(scene, &plan, policy)?;
        let mut times = vec![("top level (CPU)", t0.elapsed().as_secs_f64() * 1e3)];
        if plan.contains(&Update::Rebuild) {
            times.insert(0, ("bvh rebuild (CPU)", self.cpu_rebuild_ms));
        }
        Ok((counts(&plan), times))
    }

    fn updates_in_frame(&self) -> bool {
        // The host builds the top level from the refit roots, between the
        // refit and the tracing passes.
        false
    }

    fn destroy(&mut self, ctx: &Context) {
        self.bvh.destroy(ctx);
    }
}
