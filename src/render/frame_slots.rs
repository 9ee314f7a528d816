//! What the host reads of a finished frame after its ring slot's fence: readback buffers, pass times,
//! budget statistics, auto exposure's state, the bad-pixel counter and the scene update's results. With
//! frames in flight (vk/frame_ring.rs) each is a download copied into the slot at the end of the frame's
//! command buffer; what the host needs to interpret it (pass names, the budget's selection, the
//! update's plan) waits per slot in `Pending`.

use anyhow::{Context as _, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::scene_update::{PendingUpdate, SceneUpdate};
use super::tone::{self, ExposureState};
use super::tracer::Tracer;
use crate::gpu::shared::{RAY_COUNTER_BAD_PIXELS, RAY_COUNTER_SLOTS, RAY_COUNTER_TRUNCATED};
use crate::gpu::GpuScene;
use crate::vk::frame_ring::{Download, FrameRing, Source, Uploads};
use crate::vk::timer::{GpuTimer, Readback};
use crate::vk::{built, Buffer, Context};

/// The frames in flight: per-slot staging of host writes and downloads (one slot unless the viewer asks
/// for more), the frame passes' timer, and the offline path's command buffer and readback buffers.
pub(super) struct FrameSlots {
    ring: FrameRing,
    /// The frame being built: its slot, and whether its uploads were
    /// recorded (`begin` .. `record_downloads`).
    open: Option<(usize, bool)>,
    /// Per slot: what its frame left to read after its fence.
    pending: Vec<Pending>,
    /// The command buffer of `Renderer::render` (the viewer brings its own).
    pub cmd: vk::CommandBuffer,
    pub timer: GpuTimer,
    /// `render`'s copies of the final LDR image and of the radiance.
    pub readback_ldr: Buffer,
    pub readback_hdr: Buffer,
}

/// What one ring slot's frame left to read after its fence.
#[derive(Default)]
struct Pending {
    update: Option<PendingUpdate>,
    timer: Option<Readback>,
    counters: Option<Download>,
    exposure: Option<Download>,
    /// The budget statistics, and the selection the frame traced.
    budget: Option<(Download, Vec<u32>)>,
    /// The frame was its passes' first (see `Finished::cold`).
    cold: bool,
}

/// What a frame that recorded passes downloads besides its times.
pub(super) struct FrameReads<'a> {
    pub gpu: &'a GpuScene,
    /// Auto exposure ran: its state is read.
    pub exposure: bool,
    /// The budget's selection the frame traced (its statistics are read).
    pub budget_traced: Option<Vec<u32>>,
    pub cold: bool,
}

/// The host's reads of a completed frame.
#[derive(Default)]
pub struct Finished {
    /// GPU ms per pass (empty when the slot held no frame).
    pub timings: Vec<(&'static str, f64)>,
    /// The frame had a scene update (its times in `SceneUpdate::timings`).
    pub updated: bool,
    pub ray_counts: [u32; 3],
    pub truncated_pixels: u32,
    pub bad_pixels: u32,
    pub exposure: Option<ExposureState>,
    /// The budget's statistics and the selection they were traced with.
    pub(super) budget: Option<(Vec<u32>, Vec<u32>)>,
    /// The frame was the first of freshly built passes: a software device
    /// compiles shaders inside its timestamps, so its times say nothing.
    pub(super) cold: bool,
}

/// The frame's ray counters start at zero (staged in its ring slot).
pub(super) fn reset_counters(up: &mut Uploads, counters: &Buffer) -> Result<()> {
    up.write(counters, 0, &[0u8; RAY_COUNTER_SLOTS as usize * 4])
}

fn whole(b: &Buffer) -> Source {
    Source::Buffer { buffer: b.raw, offset: 0, size: b.size }
}

impl FrameSlots {
    /// One slot, nothing created yet.
    pub fn empty() -> Result<FrameSlots> {
        Ok(FrameSlots {
            ring: FrameRing::new(1, "frame ring")?,
            open: None,
            pending: vec![Pending::default()],
            cmd: vk::CommandBuffer::null(),
            timer: GpuTimer::empty(),
            readback_ldr: Buffer::null(),
            readback_hdr: Buffer::null(),
        })
    }

    pub fn new(ctx: &Context, extent: vk::Extent2D) -> Result<FrameSlots> {
        built(ctx, FrameSlots::empty()?, |s| {
            s.resize(ctx, extent)?;
            s.timer = GpuTimer::new(ctx, 16)?;
            s.cmd = ctx.allocate_command_buffer("frame")?;
            Ok(())
        })
    }

    /// Readback buffers for frames of `extent` (the caller has waited).
    pub fn resize(&mut self, ctx: &Context, extent: vk::Extent2D) -> Result<()> {
        let px = extent.width as u64 * extent.height as u64;
        for (buffer, name, bytes) in
            [(&mut self.readback_ldr, "readback ldr", 4), (&mut self.readback_hdr, "readback hdr", 16)]
        {
            buffer.destroy(ctx);
            let usage = vk::BufferUsageFlags::TRANSFER_DST;
            *buffer = Buffer::new(ctx, name, px * bytes, usage, MemoryLocation::GpuToCpu)?;
        }
        Ok(())
    }

    /// Starts the frame of ring slot `slot`: its host writes are staged
    /// there. Call after the slot's previous frame finished.
    pub fn begin(&mut self, slot: usize) -> Result<()> {
        anyhow::ensure!(slot < self.ring.slots(), "frame slot {slot} of a {}-slot ring", self.ring.slots());
        if self.pending[slot].timer.is_some() || self.pending[slot].update.is_some() {
            log::debug!("slot {slot}'s last frame was never finished; its results are lost");
        }
        self.ring.begin(slot)?;
        self.pending[slot] = Pending::default();
        self.open = Some((slot, false));
        Ok(())
    }

    /// The open frame's staging (`what` names the step that needs it).
    pub fn uploads(&mut self, what: &str) -> Result<Uploads<'_>> {
        let slot = self.open_slot(what)?;
        Ok(Uploads { ring: &mut self.ring, slot })
    }

    /// The open frame's slot; an error naming `what` when none is open.
    pub fn open_slot(&self, what: &str) -> Result<usize> {
        self.open.map(|(slot, _)| slot).with_context(|| format!("begin_frame() must run before {what}"))
    }

    /// Records the open frame's staged copies into `cmd`, once, before its
    /// first GPU work (the scene update or the passes).
    pub fn record_uploads(&mut self, ctx: &Context, cmd: vk::CommandBuffer) -> Result<()> {
        let open = self.open.as_mut().context("begin_frame() must run before recording")?;
        if !std::mem::replace(&mut open.1, true) {
            self.ring.record_uploads(ctx, cmd, open.0)?;
        }
        Ok(())
    }

    /// Registers the downloads of the scene update just recorded.
    pub fn download_update(
        &mut self,
        update: &SceneUpdate,
        tracer: Option<&dyn Tracer>,
        plan: Vec<crate::accel::dynamic::Update>,
    ) -> Result<()> {
        let (slot, _) = self.open.context("no open frame")?;
        self.pending[slot].update = Some(update.download(&mut self.ring, slot, tracer, plan)?);
        Ok(())
    }

    /// Registers the frame's own downloads (`frame`: it recorded passes, not only an update) and records
    /// all of the slot's into `cmd` as its last commands; closes the frame.
    pub fn record_downloads(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        frame: Option<FrameReads>,
    ) -> Result<()> {
        let (slot, _) = self.open.take().context("no open frame")?;
        let ring = &mut self.ring;
        let Some(f) = frame else { return ring.record_downloads(ctx, cmd, slot) };
        let p = &mut self.pending[slot];
        p.timer = Some(self.timer.download(ring, slot)?);
        p.counters = Some(ring.download(slot, whole(&f.gpu.ray_counters))?);
        if f.exposure {
            let size = tone::EXPOSURE_STATE_BYTES as u64;
            p.exposure =
                Some(ring.download(slot, Source::Buffer { buffer: f.gpu.exposure.raw, offset: 0, size })?);
        }
        if let Some(traced) = f.budget_traced {
            p.budget = Some((ring.download(slot, whole(&f.gpu.budget_stats))?, traced));
        }
        p.cold = f.cold;
        ring.record_downloads(ctx, cmd, slot)
    }

    /// After slot `slot`'s fence: the scene update's results (into `update`, feeding the tracer's rebuild
    /// policy) and the frame's reads. Empty when the slot held no frame.
    pub fn finish(
        &mut self,
        slot: usize,
        update: &mut SceneUpdate,
        tracer: Option<&mut (dyn Tracer + 'static)>,
    ) -> Result<Finished> {
        let p = std::mem::take(&mut self.pending[slot]);
        let ring = &self.ring;
        let updated = p.update.is_some();
        if let Some(u) = p.update {
            update.finish(ring, slot, u, tracer)?;
        }
        let Some(timer) = p.timer else { return Ok(Finished::default()) };
        let mut done =
            Finished { timings: timer.ms(ring, slot)?, updated, cold: p.cold, ..Default::default() };
        if let Some(d) = p.counters {
            let counts: Vec<u32> = bytemuck::pod_collect_to_vec(ring.read(slot, d)?);
            done.ray_counts = [counts[0], counts[1], counts[2]];
            done.truncated_pixels = counts[RAY_COUNTER_TRUNCATED as usize];
            done.bad_pixels = counts[RAY_COUNTER_BAD_PIXELS as usize];
        }
        if let Some(d) = p.exposure {
            done.exposure = Some(bytemuck::pod_read_unaligned(ring.read(slot, d)?));
        }
        if let Some((d, traced)) = p.budget {
            done.budget = Some((bytemuck::pod_collect_to_vec(ring.read(slot, d)?), traced));
        }
        Ok(done)
    }

    /// Replaces the ring by one of `slots` frames in flight; waits for the device.
    pub fn set_frames_in_flight(&mut self, ctx: &Context, slots: usize) -> Result<()> {
        unsafe { ctx.device.device_wait_idle() }
            .context("vkDeviceWaitIdle before replacing the frame ring")?;
        self.ring.destroy(ctx);
        self.ring = FrameRing::new(slots, "frame ring")?;
        self.pending = (0..slots).map(|_| Pending::default()).collect();
        self.open = None;
        Ok(())
    }

    /// The caller has waited for the device.
    pub fn destroy(&mut self, ctx: &Context) {
        if self.cmd != vk::CommandBuffer::null() {
            unsafe { ctx.device.free_command_buffers(ctx.command_pool, &[self.cmd]) };
            self.cmd = vk::CommandBuffer::null();
        }
        self.readback_ldr.destroy(ctx);
        self.readback_hdr.destroy(ctx);
        self.ring.destroy(ctx);
        self.timer.destroy(ctx);
    }
}

crate::destroy_by_method!(FrameSlots);
