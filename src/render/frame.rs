//! The pass layer. A pass declares the targets and shared buffers it reads and writes (`Access`); the
//! recorder derives every layout transition and synchronization2 barrier from that, wraps the pass in a debug
//! label and a pair of GPU timestamps, and remembers what ran: no call site writes a barrier, a label or a
//! timestamp. Deliberately small: one queue, passes in the given order, no aliasing or reordering.

use std::collections::HashMap;

use anyhow::Result;
use ash::vk;
use vk::AccessFlags2 as A;
use vk::PipelineStageFlags2 as S;

use super::targets::Targets;
use super::uses::TargetDesc;
pub use super::uses::{Access, Resource, SharedBuffer, Use};
use crate::vk::timer::{label_color, GpuTimer};
use crate::vk::Context;

/// Where a resource stands between passes.
#[derive(Clone, Copy, Debug)]
struct State {
    layout: vk::ImageLayout,
    /// The last writer's scope.
    write: (vk::PipelineStageFlags2, vk::AccessFlags2),
    /// Stages the last write has been made visible to.
    visible_to: vk::PipelineStageFlags2,
    /// Stages that read since the last write (a later write waits for them).
    readers: vk::PipelineStageFlags2,
}

/// The start of a frame: contents undefined, and everything before on the
/// queue (the previous frame) must be done with the resource.
const FRAME_START: State = State {
    layout: vk::ImageLayout::UNDEFINED,
    write: (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_WRITE),
    visible_to: vk::PipelineStageFlags2::NONE,
    readers: vk::PipelineStageFlags2::ALL_COMMANDS,
};

/// Records passes into one command buffer.
pub struct Recorder<'a> {
    pub ctx: &'a Context,
    pub cmd: vk::CommandBuffer,
    timer: &'a mut GpuTimer,
    targets: Option<&'a Targets>,
    /// Images from outside the frame's targets (the swapchain's), by the
    /// declaration passes use them under: (image, aspect).
    imported: HashMap<&'static str, (vk::Image, vk::ImageAspectFlags)>,
    images: HashMap<&'static str, State>,
    buffers: HashMap<SharedBuffer, State>,
    /// Names of the passes recorded, in order.
    pub recorded: Vec<&'static str>,
    /// Drain each pass before its end timestamp (CPU devices, see `pass`); not under synchronization
    /// validation, where the drain would hide a missing derived barrier.
    drain_for_timing: bool,
}

impl<'a> Recorder<'a> {
    /// Starts recording into `cmd` (already begun): resets `timer`.
    pub fn new(
        ctx: &'a Context,
        cmd: vk::CommandBuffer,
        timer: &'a mut GpuTimer,
        targets: Option<&'a Targets>,
    ) -> Recorder<'a> {
        timer.begin_frame(ctx, cmd);
        Recorder {
            ctx,
            cmd,
            timer,
            targets,
            imported: HashMap::new(),
            images: HashMap::new(),
            buffers: HashMap::new(),
            recorded: Vec::new(),
            drain_for_timing: ctx.caps.device_type == vk::PhysicalDeviceType::CPU && !ctx.sync_validation,
        }
    }

    /// Records one pass: barriers for `uses`, then `f` inside a debug label
    /// and a pair of timestamps. `shader` is the pass's shader stage.
    pub fn pass<R>(
        &mut self,
        name: &'static str,
        shader: vk::PipelineStageFlags2,
        uses: &[Use],
        f: impl FnOnce(vk::CommandBuffer) -> Result<R>,
    ) -> Result<R> {
        self.recorded.push(name);
        let (ctx, cmd) = (self.ctx, self.cmd);
        let barriers = self.barrier_list(shader, uses)?;
        ctx.begin_label(cmd, name, label_color(name));
        let slot = self.timer.begin(ctx, cmd, name);
        barriers.record(ctx, cmd);
        let r = f(cmd);
        if self.drain_for_timing {
            // A CPU device writes timestamps without waiting for the work before them; a barrier makes it
            // finish this pass first, so the pass is charged its own work.
            let all = (S::ALL_COMMANDS, A::MEMORY_WRITE);
            crate::vk::memory_barrier(ctx, cmd, all, (S::ALL_COMMANDS, A::MEMORY_READ | A::MEMORY_WRITE));
        }
        if let Some(slot) = slot {
            self.timer.end(ctx, cmd, slot);
        }
        ctx.end_label(cmd);
        r
    }

    /// Makes `image`, which the frame does not own (a swapchain image), usable by passes as `desc`: its
    /// barriers are derived like a target's, from undefined contents that earlier work on the queue (the
    /// acquire's semaphore wait) may still touch.
    pub fn import(&mut self, desc: &'static TargetDesc, image: vk::Image, aspect: vk::ImageAspectFlags) {
        self.imported.insert(desc.name, (image, aspect));
    }

    /// Records only the barriers that make `uses` safe (no pass, label or
    /// timestamp): an imported image's hand-over, e.g. to presentation.
    pub fn transition(&mut self, uses: &[Use]) -> Result<()> {
        let barriers = self.barrier_list(vk::PipelineStageFlags2::NONE, uses)?;
        barriers.record(self.ctx, self.cmd);
        Ok(())
    }

    /// Where `t` stands at the start of the frame: undefined, or for a
    /// kept target laid out by an earlier frame, its contents in GENERAL.
    fn frame_start(&self, t: &'static TargetDesc) -> State {
        let laid_out = t.kept && self.targets.and_then(|ts| ts.get(t)).is_some_and(|i| i.laid_out.get());
        if laid_out {
            State { layout: vk::ImageLayout::GENERAL, ..FRAME_START }
        } else {
            FRAME_START
        }
    }

    /// The barriers that make `uses` safe after everything recorded so far.
    fn barrier_list(&mut self, shader: vk::PipelineStageFlags2, uses: &[Use]) -> Result<Barriers> {
        let accel = self.ctx.rt.acceleration_structure;
        // Several uses of one resource in a pass merge into one scope.
        let mut merged: Vec<(Resource, Access, vk::PipelineStageFlags2, vk::AccessFlags2, bool)> = Vec::new();
        for u in uses {
            let (stage, access) = u.access.scope(shader, accel);
            match merged.iter_mut().find(|m| m.0 == u.resource) {
                Some(m) => {
                    anyhow::ensure!(m.1.layout() == u.access.layout(), "one pass, two layouts of one image");
                    m.2 |= stage;
                    m.3 |= access;
                    m.4 |= u.access.writes();
                }
                None => merged.push((u.resource, u.access, stage, access, u.access.writes())),
            }
        }
        let mut images = Vec::new();
        let (mut mem_src, mut mem_dst) = ((S::NONE, A::NONE), (S::NONE, A::NONE));
        for (res, first, stage, access, writes) in merged {
            let state = match res {
                Resource::Image(t) => {
                    let start = self.frame_start(t);
                    self.images.entry(t.name).or_insert(start)
                }
                Resource::Buffer(b) => self.buffers.entry(b).or_insert(FRAME_START),
            };
            let layout = match res {
                Resource::Image(_) => first.layout(),
                Resource::Buffer(_) => vk::ImageLayout::UNDEFINED,
            };
            let transition = layout != state.layout;
            // Write after write / read, or a layout change: wait for the writer and the readers. Read after
            // write: wait for the writer, once per reading stage.
            let src = if writes || transition {
                Some((state.write.0 | state.readers, state.write.1))
            } else if !state.visible_to.contains(stage) {
                Some(state.write)
            } else {
                None
            };
            if let Some(src) = src {
                match res {
                    Resource::Image(t) => {
                        let (raw, aspect) = image_of(self.targets, &self.imported, t)?;
                        let old = if first.discards() { vk::ImageLayout::UNDEFINED } else { state.layout };
                        if let Some(img) = self.targets.and_then(|ts| ts.get(t)) {
                            img.laid_out.set(t.kept && layout == vk::ImageLayout::GENERAL);
                        }
                        images.push(
                            vk::ImageMemoryBarrier2::default()
                                .image(raw)
                                .old_layout(old)
                                .new_layout(layout)
                                .src_stage_mask(nonempty(src.0))
                                .src_access_mask(src.1)
                                .dst_stage_mask(stage)
                                .dst_access_mask(access)
                                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                                .subresource_range(
                                    vk::ImageSubresourceRange::default()
                                        .aspect_mask(aspect)
                                        .level_count(1)
                                        .layer_count(1),
                                ),
                        );
                    }
                    Resource::Buffer(_) => {
                        mem_src = (mem_src.0 | src.0, mem_src.1 | src.1);
                        mem_dst = (mem_dst.0 | stage, mem_dst.1 | access);
                    }
                }
            }
            *state = if writes {
                State { layout, write: (stage, access & write_bits()), visible_to: S::NONE, readers: S::NONE }
            } else {
                let visible_to = if transition { stage } else { state.visible_to | stage };
                // A later reader in another stage chains through this
                // barrier (it may have carried the layout transition).
                let chain = if src.is_some() { stage } else { S::NONE };
                let write = (state.write.0 | chain, state.write.1);
                State { layout, write, visible_to, readers: state.readers | stage }
            };
        }
        let memory: Vec<_> = if mem_dst.0.is_empty() {
            Vec::new()
        } else {
            vec![vk::MemoryBarrier2::default()
                .src_stage_mask(nonempty(mem_src.0))
                .src_access_mask(mem_src.1)
                .dst_stage_mask(mem_dst.0)
                .dst_access_mask(mem_dst.1)]
        };
        Ok(Barriers { images, memory })
    }
}

/// The image behind `t` and its aspect: a target, or an imported image.
fn image_of(
    targets: Option<&Targets>,
    imported: &HashMap<&'static str, (vk::Image, vk::ImageAspectFlags)>,
    t: &'static TargetDesc,
) -> Result<(vk::Image, vk::ImageAspectFlags)> {
    if let Some(img) = targets.and_then(|ts| ts.get(t)) {
        return Ok((img.raw, img.aspect));
    }
    imported.get(t.name).copied().ok_or_else(|| anyhow::anyhow!("target '{}' used but not allocated", t.name))
}

/// The barriers before one pass.
struct Barriers {
    images: Vec<vk::ImageMemoryBarrier2<'static>>,
    memory: Vec<vk::MemoryBarrier2<'static>>,
}

impl Barriers {
    fn record(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        if !self.images.is_empty() || !self.memory.is_empty() {
            let dep = vk::DependencyInfo::default()
                .image_memory_barriers(&self.images)
                .memory_barriers(&self.memory);
            unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &dep) };
        }
    }
}

fn nonempty(s: vk::PipelineStageFlags2) -> vk::PipelineStageFlags2 {
    if s.is_empty() {
        vk::PipelineStageFlags2::TOP_OF_PIPE
    } else {
        s
    }
}

fn write_bits() -> vk::AccessFlags2 {
    A::SHADER_STORAGE_WRITE
        | A::COLOR_ATTACHMENT_WRITE
        | A::DEPTH_STENCIL_ATTACHMENT_WRITE
        | A::ACCELERATION_STRUCTURE_WRITE_KHR
        | A::TRANSFER_WRITE
        | A::MEMORY_WRITE
}
