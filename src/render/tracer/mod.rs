//! One tracing interface, three implementations: ray queries (`query.rs`), the RT pipeline
//! (`pipeline.rs`) and our compute BVH (`compute.rs`). A tracer owns its acceleration data, records
//! its per-frame updates and hands out the tracing passes' pipelines and set 2, so no pass branches on
//! the backend: a pass names its shader ("direct") and gets a `Kernel`.

pub mod compute;
pub mod hardware;
pub mod pipeline;
pub mod query;

use anyhow::Result;
use ash::vk;

use super::frame::Recorder;
use super::kernel::Kernel;
use super::shading::Backend;
use crate::accel::dynamic::{RebuildPolicy, Update};
use crate::gpu::GpuScene;
use crate::scene::{Aabb, Scene};
use crate::vk::frame_ring::{Source, Uploads};
use crate::vk::pipeline::{DescriptorSet, Specialization};
use crate::vk::Context;

/// What an update refit and rebuilt.
#[derive(Clone, Copy, Debug, Default)]
pub struct UpdateCounts {
    pub refits: usize,
    pub rebuilds: usize,
}

/// What building a tracer's structures cost at load: wall ms and the bytes of its GPU buffers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AccelStats {
    pub build_ms: f64,
    pub bytes: u64,
}

pub trait Tracer {
    fn backend(&self) -> Backend;

    /// The load-time build's cost and the structures' GPU bytes (nodes, triangles, instances,
    /// scratch kept for updates).
    fn accel_stats(&self) -> AccelStats;

    /// The pipeline of tracing pass `pass`, from its shader for this
    /// backend (`{pass}_query`, `{pass}_compute` or `{pass}.rgen`).
    fn kernel(
        &self,
        ctx: &Context,
        pass: &str,
        layout: vk::PipelineLayout,
        spec: &Specialization,
    ) -> Result<Kernel>;

    /// Set 2 of the tracing passes.
    fn set(&self) -> &DescriptorSet;

    /// Host work before an update is recorded (instances moved, skinned
    /// meshes deformed): which structures refit or rebuild, CPU rebuilds,
    /// top-level records, all staged in the frame's ring slot (a frame may
    /// be in flight). Returns the plan, for `finish_update` of this frame.
    fn prepare_update(
        &mut self,
        up: &mut Uploads,
        scene: &Scene,
        gpu: &GpuScene,
        policy: &RebuildPolicy,
    ) -> Result<Vec<Update>>;

    /// Records the update's GPU passes (after skinning, before tracing).
    fn record_update(&mut self, rec: &mut Recorder, scene: &Scene, gpu: &GpuScene) -> Result<()>;

    /// What the update's finish reads back at the end of its frame.
    fn readback(&self) -> Option<Source>;

    /// After the update's frame completed: feeds the rebuild policy
    /// (`plan`: `prepare_update`'s; `skinned_bounds`: the skinning pass's
    /// deformed bounds per slot; `readback`: the bytes of `readback`).
    /// Returns the counts and host-side times of the update.
    fn finish_update(
        &mut self,
        plan: &[Update],
        skinned_bounds: &[Aabb],
        readback: Option<&[u8]>,
        policy: &RebuildPolicy,
    ) -> Result<(UpdateCounts, Vec<(&'static str, f64)>)>;

    fn destroy(&mut self, ctx: &Context);
}

/// Builds the tracer for `backend` over `scene` (acceleration structures
/// or our BVH included).
pub fn create(ctx: &Context, backend: Backend, scene: &Scene, gpu: &GpuScene) -> Result<Box<dyn Tracer>> {
    Ok(match backend {
        Backend::Compute => Box::new(compute::ComputeTracer::new(ctx, scene, gpu)?),
        Backend::Query => Box::new(hardware::HardwareTracer::new(ctx, scene, gpu, backend, query::kernel)?),
        Backend::Pipeline => {
            Box::new(hardware::HardwareTracer::new(ctx, scene, gpu, backend, pipeline::kernel)?)
        }
        Backend::Auto => anyhow::bail!("Backend::Auto must be resolved before a tracer is created"),
    })
}
