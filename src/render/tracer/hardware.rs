//! The acceleration structures of the hardware backends (ray query and RT
//! pipeline): static BLASes built once, skinned BLASes refit (or rebuilt,
//! per the rebuild policy) and the TLAS rebuilt whenever something moved.
//! The two backends differ only in the pipelines of their passes.

use anyhow::Result;
use ash::vk;

use super::{Tracer, UpdateCounts};
use crate::accel::dynamic::{RebuildPolicy, Update};
use crate::accel::SceneAccel;
use crate::gpu::shared::TRACE_TLAS;
use crate::gpu::GpuScene;
use crate::render::frame::{Access, Recorder, SharedBuffer, Use};
use crate::render::kernel::Kernel;
use crate::render::shading::Backend;
use crate::scene::{Aabb, Scene};
use crate::vk::frame_ring::{Source, Uploads};
use crate::vk::pipeline::{Binding, DescriptorSet, Specialization};
use crate::vk::Context;

type KernelFn = fn(&Context, &str, vk::PipelineLayout, &Specialization) -> Result<Kernel>;

pub struct HardwareTracer {
    accel: SceneAccel,
    set: DescriptorSet,
    /// The TLAS the set holds.
    bound_tlas: vk::AccelerationStructureKHR,
    kernel: KernelFn,
    backend: Backend,
    /// What the update being recorded does to each skinned BLAS (its
    /// `finish_update` gets a copy: frames in flight record later updates).
    plan: Vec<Update>,
}

impl HardwareTracer {
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        gpu: &GpuScene,
        backend: Backend,
        kernel: KernelFn,
    ) -> Result<HardwareTracer> {
        let accel = SceneAccel::build(ctx, scene, gpu)?;
        let set = DescriptorSet::numbered(
            ctx,
            "trace set (TLAS)",
            &[(TRACE_TLAS, Binding::one(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR))],
        )?;
        set.write_acceleration_structure(ctx, TRACE_TLAS, accel.tlas.raw);
        let bound_tlas = accel.tlas.raw;
        Ok(HardwareTracer { accel, set, bound_tlas, kernel, backend, plan: Vec::new() })
    }
}

impl Tracer for HardwareTracer {
    fn backend(&self) -> Backend {
        self.backend
    }

    fn accel_stats(&self) -> super::AccelStats {
        super::AccelStats { build_ms: self.accel.build_ms, bytes: self.accel.bytes() }
    }

    fn kernel(
        &self,
        ctx: &Context,
        pass: &str,
        layout: vk::PipelineLayout,
        spec: &Specialization,
    ) -> Result<Kernel> {
        (self.kernel)(ctx, pass, layout, spec)
    }

    fn set(&self) -> &DescriptorSet {
        &self.set
    }

    fn prepare_update(
        &mut self,
        up: &mut Uploads,
        scene: &Scene,
        _: &GpuScene,
        policy: &RebuildPolicy,
    ) -> Result<Vec<Update>> {
        self.plan = match &self.accel.dynamic {
            Some(d) => d.blases.iter().map(|b| b.state.next(policy)).collect(),
            None => Vec::new(),
        };
        self.accel.write_instances(up, scene)?;
        Ok(self.plan.clone())
    }

    fn record_update(&mut self, rec: &mut Recorder, scene: &Scene, gpu: &GpuScene) -> Result<()> {
        let (ctx, accel, plan) = (rec.ctx, &mut self.accel, &self.plan);
        let geometry = Use::buffer(SharedBuffer::Geometry, Access::AsBuildRead);
        let structures = Use::buffer(SharedBuffer::Accel, Access::AsBuildWrite);
        if !plan.is_empty() {
            let name = if plan.contains(&Update::Rebuild) { "blas rebuild" } else { "blas refit" };
            rec.pass(name, vk::PipelineStageFlags2::NONE, &[geometry, structures], |cmd| {
                accel.record_dynamic(ctx, cmd, gpu, plan);
                Ok(())
            })?;
        }
        rec.pass("tlas build", vk::PipelineStageFlags2::NONE, &[structures], |cmd| {
            accel.record_tlas(ctx, cmd, scene)
        })?;
        // A TLAS that had to grow is a new object (`record_tlas` waited for
        // the device first); nothing recorded so far binds the set, so
        // rewriting it here is allowed. Only then: a frame in flight may use
        // the set, and updating it under that frame is undefined.
        if self.bound_tlas != self.accel.tlas.raw {
            self.set.write_acceleration_structure(ctx, TRACE_TLAS, self.accel.tlas.raw);
            self.bound_tlas = self.accel.tlas.raw;
        }
        Ok(())
    }

    fn readback(&self) -> Option<Source> {
        None
    }

    fn finish_update(
        &mut self,
        plan: &[Update],
        skinned_bounds: &[Aabb],
        _: Option<&[u8]>,
        policy: &RebuildPolicy,
    ) -> Result<(UpdateCounts, Vec<(&'static str, f64)>)> {
        if let Some(d) = &mut self.accel.dynamic {
            for ((b, bounds), u) in d.blases.iter_mut().zip(skinned_bounds).zip(plan) {
                b.state.done(*u, bounds, policy);
            }
        }
        Ok((counts(plan), Vec::new()))
    }

    fn destroy(&mut self, ctx: &Context) {
        self.set.destroy(ctx);
        self.accel.destroy(ctx);
    }
}

pub fn counts(plan: &[Update]) -> UpdateCounts {
    let n = |k: Update| plan.iter().filter(|u| **u == k).count();
    UpdateCounts { refits: n(Update::Refit), rebuilds: n(Update::Rebuild) }
}
