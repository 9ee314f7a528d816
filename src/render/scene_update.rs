//! The scene update's owner: skinning and the tracer's refit / rebuild of what moved, recorded at a
//! frame's start (or in a submission of its own), its GPU times and counts read after the fence.

use anyhow::Result;
use ash::vk;

use super::frame::{Access, Recorder, SharedBuffer, Use};
use super::skinning::Skinning;
use super::tracer::Tracer;
use crate::accel::dynamic::{RebuildPolicy, Update};
use crate::gpu::GpuScene;
use crate::scene::Scene;
use crate::vk::frame_ring::{Download, FrameRing, Uploads};
use crate::vk::timer::{GpuTimer, Readback};
use crate::vk::{built, Context};

pub struct SceneUpdate {
    /// Skinning of skinned instances, if the scene has any.
    skinning: Option<Skinning>,
    /// When skinned acceleration structures are rebuilt instead of refit.
    pub policy: RebuildPolicy,
    /// The command buffer of an update submitted on its own (`update_scene`).
    pub(super) cmd: vk::CommandBuffer,
    timer: GpuTimer,
    /// GPU ms per pass of the last finished update (plus the host's share), for benchmarks and the viewer.
    pub timings: Vec<(&'static str, f64)>,
    /// Skinned structures refit / rebuilt by the last finished update.
    pub counts: [usize; 2],
}

/// A recorded update awaiting its frame's fence.
pub(super) struct PendingUpdate {
    timer: Readback,
    bounds: Option<Download>,
    readback: Option<Download>,
    plan: Vec<Update>,
}

impl SceneUpdate {
    /// Nothing created yet.
    pub(super) fn empty() -> SceneUpdate {
        SceneUpdate {
            skinning: None,
            policy: RebuildPolicy::default(),
            cmd: vk::CommandBuffer::null(),
            timer: GpuTimer::empty(),
            timings: Vec::new(),
            counts: [0; 2],
        }
    }

    pub(super) fn new(ctx: &Context, scene: &Scene, gpu: &GpuScene) -> Result<SceneUpdate> {
        built(ctx, SceneUpdate::empty(), |u| {
            u.skinning = Skinning::new(ctx, scene, gpu)?;
            u.cmd = ctx.allocate_command_buffer("scene update")?;
            u.timer = GpuTimer::new(ctx, 8)?;
            Ok(())
        })
    }

    /// Host work before the update is recorded, staged in the frame's slot: moved transforms and lights,
    /// joint matrices, and the tracer's refit / rebuild decisions (returned, for `finish`).
    pub(super) fn plan(
        &self,
        up: &mut Uploads,
        scene: &Scene,
        gpu: &mut GpuScene,
        tracer: Option<&mut (dyn Tracer + 'static)>,
    ) -> Result<Vec<Update>> {
        gpu.update_dynamic(up, scene)?;
        if let Some(s) = &self.skinning {
            s.write(up, scene, gpu.origin)?;
        }
        match tracer {
            Some(t) => t.prepare_update(up, scene, gpu, &self.policy),
            None => Ok(Vec::new()),
        }
    }

    /// The update's GPU passes, timed by its own timer.
    pub(super) fn record(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        scene: &Scene,
        gpu: &GpuScene,
        tracer: Option<&mut (dyn Tracer + 'static)>,
    ) -> Result<()> {
        let mut rec = Recorder::new(ctx, cmd, &mut self.timer, None);
        if let Some(s) = &self.skinning {
            let uses = [Use::buffer(SharedBuffer::Geometry, Access::ShaderWrite)];
            rec.pass("skinning", vk::PipelineStageFlags2::COMPUTE_SHADER, &uses, |cmd| {
                s.record(ctx, cmd);
                Ok(())
            })?;
        }
        if let Some(t) = tracer {
            t.record_update(&mut rec, scene, gpu)?;
        }
        Ok(())
    }

    /// Registers the downloads of the update just recorded into `slot`.
    pub(super) fn download(
        &self,
        ring: &mut FrameRing,
        slot: usize,
        tracer: Option<&dyn Tracer>,
        plan: Vec<Update>,
    ) -> Result<PendingUpdate> {
        let timer = self.timer.download(ring, slot)?;
        let bounds = self.skinning.as_ref().map(|s| ring.download(slot, s.bounds_source())).transpose()?;
        let readback = tracer.and_then(|t| t.readback()).map(|s| ring.download(slot, s)).transpose()?;
        Ok(PendingUpdate { timer, bounds, readback, plan })
    }

    /// After `slot`'s fence: the update's times and counts, and the
    /// tracer's rebuild policy fed with what it measured.
    pub(super) fn finish(
        &mut self,
        ring: &FrameRing,
        slot: usize,
        u: PendingUpdate,
        tracer: Option<&mut (dyn Tracer + 'static)>,
    ) -> Result<()> {
        self.timings = u.timer.ms(ring, slot)?;
        let bounds = match (&self.skinning, u.bounds) {
            (Some(s), Some(d)) => s.bounds(ring.read(slot, d)?)?,
            _ => Vec::new(),
        };
        let readback = u.readback.map(|d| ring.read(slot, d)).transpose()?;
        self.counts = [0; 2];
        if let Some(t) = tracer {
            let (counts, host) = t.finish_update(&u.plan, &bounds, readback, &self.policy)?;
            self.timings.extend(host);
            self.counts = [counts.refits, counts.rebuilds];
        }
        Ok(())
    }

    /// The caller has waited for the device.
    pub fn destroy(&mut self, ctx: &Context) {
        if self.cmd != vk::CommandBuffer::null() {
            unsafe { ctx.device.free_command_buffers(ctx.command_pool, &[self.cmd]) };
            self.cmd = vk::CommandBuffer::null();
        }
        self.timer.destroy(ctx);
        if let Some(mut s) = self.skinning.take() {
            s.destroy(ctx);
        }
    }
}

crate::destroy_by_method!(SceneUpdate);
