//! The pass layer. A pass declares the images (render targets) and the
//! shared buffers it reads and writes, with how (`Access`); the recorder
//! derives every layout transition and synchronization2 barrier from those
//! declarations, wraps the pass in a debug label and a pair of GPU
//! timestamps, and remembers what ran. Nothing at a call site writes a
//! barrier, a label or a timestamp. (Deliberately small: one queue, passes
//! in the order given, no aliasing or reordering.)

use std::collections::HashMap;

use anyhow::Result;
use ash::vk;
use vk::AccessFlags2 as A;
use vk::PipelineStageFlags2 as S;

use super::targets::{TargetDesc, Targets};
use crate::vk::timer::{label_color, GpuTimer};
use crate::vk::Context;

/// Buffers shared between passes, tracked like images (global barriers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SharedBuffer {
    /// The one vertex/index copy (the skinning pass writes its skinned ranges).
    Geometry,
    /// The tracer's acceleration data: TLAS/BLASes or the compute BVH.
    Accel,
    /// The auto-exposure state and the luminance reduction's scratch.
    Exposure,
    /// The frame counters (rays by kind, truncated and bad pixels).
    Counters,
    /// The ray-tracing budget's per-object statistics.
    Budget,
}

/// How a pass uses a resource. Shader accesses happen in the pass's own
/// shader stage (compute or ray tracing), the rest in fixed stages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// texelFetch / texture from a sampled image.
    Sampled,
    /// imageLoad.
    StorageRead,
    /// imageStore (every pixel the readers read is written).
    StorageWrite,
    /// Colour attachment, cleared and written.
    ColorAttachment,
    /// Depth attachment, cleared, tested and written.
    DepthAttachment,
    /// Source of a copy or blit.
    TransferRead,
    /// Storage-buffer or acceleration-structure reads in shaders.
    ShaderRead,
    /// Storage-buffer writes in shaders.
    ShaderWrite,
    /// Vertex pulling and index fetch of a raster pass.
    VertexInput,
    /// Input of an acceleration-structure build.
    AsBuildRead,
    /// Acceleration-structure build or refit output (read too: refits).
    AsBuildWrite,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    Image(&'static TargetDesc),
    Buffer(SharedBuffer),
}

/// One declared use.
#[derive(Clone, Copy, Debug)]
pub struct Use {
    pub resource: Resource,
    pub access: Access,
    /// The pass also samples the image in between its own barriers (the
    /// G-buffer pass's occlusion pyramid reads its depth): the target is
    /// allocated with SAMPLED usage too, only where a pass says so.
    pub sampled_within: bool,
}

impl Use {
    pub const fn image(t: &'static TargetDesc, access: Access) -> Use {
        Use { resource: Resource::Image(t), access, sampled_within: false }
    }
    pub const fn buffer(b: SharedBuffer, access: Access) -> Use {
        Use { resource: Resource::Buffer(b), access, sampled_within: false }
    }
    /// This use, with the pass sampling the image itself (`sampled_within`).
    pub const fn sampled_within(self) -> Use {
        Use { sampled_within: true, ..self }
    }
}

impl Access {
    pub fn writes(self) -> bool {
        matches!(
            self,
            Access::StorageWrite
                | Access::ColorAttachment
                | Access::DepthAttachment
                | Access::ShaderWrite
                | Access::AsBuildWrite
        )
    }

    /// Whether the previous contents are irrelevant (whole image overwritten).
    fn discards(self) -> bool {
        matches!(self, Access::ColorAttachment | Access::DepthAttachment)
    }

    /// The image layout this access needs.
    pub fn layout(self) -> vk::ImageLayout {
        match self {
            Access::Sampled => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Access::ColorAttachment => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            Access::DepthAttachment => vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            Access::TransferRead => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            _ => vk::ImageLayout::GENERAL,
        }
    }

    /// Stages and access flags, with `shader` the pass's shader stage(s).
    fn scope(
        self,
        shader: vk::PipelineStageFlags2,
        accel: bool,
    ) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
        let as_read = if accel { A::ACCELERATION_STRUCTURE_READ_KHR } else { A::NONE };
        match self {
            Access::Sampled => (shader, A::SHADER_SAMPLED_READ),
            Access::StorageRead => (shader, A::SHADER_STORAGE_READ),
            Access::StorageWrite => (shader, A::SHADER_STORAGE_WRITE),
            Access::ColorAttachment => (S::COLOR_ATTACHMENT_OUTPUT, A::COLOR_ATTACHMENT_WRITE),
            Access::DepthAttachment => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
            ),
            Access::TransferRead => (S::COPY | S::BLIT, A::TRANSFER_READ),
            Access::ShaderRead => (shader, A::SHADER_READ | as_read),
            Access::ShaderWrite => (shader, A::SHADER_STORAGE_WRITE),
            Access::VertexInput => {
                (S::VERTEX_SHADER | S::INDEX_INPUT, A::SHADER_STORAGE_READ | A::INDEX_READ)
            }
            Access::AsBuildRead => (S::ACCELERATION_STRUCTURE_BUILD_KHR, A::SHADER_READ),
            Access::AsBuildWrite => (
                S::ACCELERATION_STRUCTURE_BUILD_KHR,
                A::ACCELERATION_STRUCTURE_READ_KHR | A::ACCELERATION_STRUCTURE_WRITE_KHR,
            ),
        }
    }
}

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
    images: HashMap<&'static str, State>,
    buffers: HashMap<SharedBuffer, State>,
    /// Names of the passes recorded, in order.
    pub recorded: Vec<&'static str>,
    /// Drain each pass before its end timestamp (CPU devices, see `pass`;
    /// not under synchronization validation, where the drain would hide a
    /// missing derived barrier).
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
            // A CPU device writes timestamps without waiting for the work
            // before them; a barrier makes it finish this pass first, so the
            // pass is charged its own work.
            let all = (S::ALL_COMMANDS, A::MEMORY_WRITE);
            crate::vk::memory_barrier(ctx, cmd, all, (S::ALL_COMMANDS, A::MEMORY_READ | A::MEMORY_WRITE));
        }
        if let Some(slot) = slot {
            self.timer.end(ctx, cmd, slot);
        }
        ctx.end_label(cmd);
        r
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
            // Write after write / read, or a layout change: wait for the
            // writer and the readers. Read after write: wait for the writer,
            // once per reading stage.
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
                        let img = self
                            .targets
                            .and_then(|ts| ts.get(t))
                            .ok_or_else(|| anyhow::anyhow!("target '{}' used but not allocated", t.name))?;
                        let old = if first.discards() { vk::ImageLayout::UNDEFINED } else { state.layout };
                        img.laid_out.set(t.kept && layout == vk::ImageLayout::GENERAL);
                        images.push(
                            vk::ImageMemoryBarrier2::default()
                                .image(img.raw)
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
                                        .aspect_mask(img.aspect)
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
