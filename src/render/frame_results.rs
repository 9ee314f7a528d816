//! What the host reads of a finished frame, after its ring slot's fence:
//! the readback buffers, pass times, the budget's statistics, auto
//! exposure's state, the bad-pixel counter and the scene update's results.
//! With frames in flight (vk/frame_ring.rs) each of these is a download
//! copied at the end of the frame's command buffer into its slot, and
//! what the host needs to interpret it (pass names, the budget's
//! selection, the update's plan) waits per slot in `Pending`.

use anyhow::{Context as _, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{budget, tone, ExposureState, RenderSettings, Renderer};
use crate::accel::dynamic::Update;
use crate::gpu::shared::{RAY_COUNTER_BAD_PIXELS, RAY_COUNTER_SLOTS, RAY_COUNTER_TRUNCATED};
use crate::scene::{Camera, Scene};
use crate::vk::frame_ring::{Download, FrameRing, Source, Uploads};
use crate::vk::timer::Readback;
use crate::vk::{Buffer, Context};

pub(super) fn readback_buffers(ctx: &Context, extent: vk::Extent2D) -> Result<(Buffer, Buffer)> {
    let px = extent.width as u64 * extent.height as u64;
    let buffer = |name, bytes| {
        Buffer::new(ctx, name, px * bytes, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)
    };
    let ldr = buffer("readback ldr", 4)?;
    match buffer("readback hdr", 16) {
        Ok(hdr) => Ok((ldr, hdr)),
        Err(e) => {
            let mut ldr = ldr;
            ldr.destroy(ctx);
            Err(e)
        }
    }
}

/// A recorded scene update awaiting its frame's fence.
pub(super) struct PendingUpdate {
    timer: Readback,
    bounds: Option<Download>,
    readback: Option<Download>,
    plan: Vec<Update>,
}

/// What one ring slot's frame left to read after its fence.
#[derive(Default)]
pub(super) struct Pending {
    update: Option<PendingUpdate>,
    timer: Option<Readback>,
    counters: Option<Download>,
    exposure: Option<Download>,
    /// The budget statistics, and the selection the frame traced.
    budget: Option<(Download, Vec<u32>)>,
    /// The frame was its passes' first (see `Renderer::passes_new`).
    cold: bool,
}

/// The host's reads of a completed frame.
#[derive(Default)]
pub struct Finished {
    /// GPU ms per pass (empty when the slot held no frame).
    pub timings: Vec<(&'static str, f64)>,
    /// The frame had a scene update (its times in `update_timings`).
    pub updated: bool,
    pub ray_counts: [u32; 3],
    pub truncated_pixels: u32,
    pub bad_pixels: u32,
    pub exposure: Option<ExposureState>,
    /// The budget's statistics and the selection they were traced with.
    budget: Option<(Vec<u32>, Vec<u32>)>,
    cold: bool,
}

/// The frame's ray counters start at zero (staged in its ring slot).
pub(super) fn reset_counters(up: &mut Uploads, counters: &Buffer) -> Result<()> {
    up.write(counters, 0, &[0u8; RAY_COUNTER_SLOTS as usize * 4])
}

fn whole(b: &Buffer) -> Source {
    Source::Buffer { buffer: b.raw, offset: 0, size: b.size }
}

impl Renderer {
    /// Starts building the frame of ring slot `slot` (the viewer's frame
    /// slot; offline paths use 0): its host writes are staged there. Call
    /// after the slot's previous frame finished (`finish_frame`).
    pub fn begin_frame(&mut self, slot: usize) -> Result<()> {
        anyhow::ensure!(slot < self.ring.slots(), "frame slot {slot} of a {}-slot ring", self.ring.slots());
        if self.pending[slot].timer.is_some() || self.pending[slot].update.is_some() {
            log::debug!("slot {slot}'s last frame was never finished; its results are lost");
        }
        self.ring.begin(slot)?;
        self.pending[slot] = Pending::default();
        self.open = Some((slot, false));
        Ok(())
    }

    /// Records the open frame's staged copies into `cmd`, once, before its
    /// first GPU work (the scene update or the passes).
    pub(super) fn record_uploads(&mut self, ctx: &Context, cmd: vk::CommandBuffer) -> Result<()> {
        let open = self.open.as_mut().context("begin_frame() must run before recording")?;
        if !std::mem::replace(&mut open.1, true) {
            self.ring.record_uploads(ctx, cmd, open.0)?;
        }
        Ok(())
    }

    /// Registers the downloads of the scene update just recorded.
    pub(super) fn download_update(&mut self, plan: Vec<Update>) -> Result<()> {
        let (slot, _) = self.open.context("no open frame")?;
        let ring = &mut self.ring;
        let timer = self.update_timer.download(ring, slot)?;
        let bounds = self.skinning.as_ref().map(|s| ring.download(slot, s.bounds_source())).transpose()?;
        let source = self.tracer.as_ref().and_then(|t| t.readback());
        let readback = source.map(|s| ring.download(slot, s)).transpose()?;
        self.pending[slot].update = Some(PendingUpdate { timer, bounds, readback, plan });
        Ok(())
    }

    /// Registers the frame's own downloads (with `frame`: it recorded the
    /// passes, not only an update) and records all of the slot's into
    /// `cmd` (its last commands); closes the frame.
    pub(super) fn record_downloads(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        frame: bool,
    ) -> Result<()> {
        let (slot, _) = self.open.take().context("no open frame")?;
        let ring = &mut self.ring;
        if !frame {
            return ring.record_downloads(ctx, cmd, slot);
        }
        let p = &mut self.pending[slot];
        p.timer = Some(self.timer.download(ring, slot)?);
        p.counters = Some(ring.download(slot, whole(&self.gpu.ray_counters))?);
        if self.config.is_some_and(|c| c.luminance) {
            let size = tone::EXPOSURE_STATE_BYTES as u64;
            p.exposure =
                Some(ring.download(slot, Source::Buffer { buffer: self.gpu.exposure.raw, offset: 0, size })?);
        }
        if let Some(traced) = self.budget_traced.take() {
            p.budget = Some((ring.download(slot, whole(&self.gpu.budget_stats))?, traced));
        }
        p.cold = self.recorded_cold;
        ring.record_downloads(ctx, cmd, slot)
    }

    /// After slot `slot`'s fence: the scene update's results (into
    /// `update_timings` / `update_counts`, and the tracer's rebuild policy)
    /// and the frame's reads. Empty when the slot held no frame.
    pub fn finish_frame(&mut self, slot: usize) -> Result<Finished> {
        let p = std::mem::take(&mut self.pending[slot]);
        let ring = &self.ring;
        let updated = p.update.is_some();
        if let Some(u) = p.update {
            self.update_timings = u.timer.ms(ring, slot)?;
            let bounds = match (&self.skinning, u.bounds) {
                (Some(s), Some(d)) => s.bounds(ring.read(slot, d)?)?,
                _ => Vec::new(),
            };
            let readback = u.readback.map(|d| ring.read(slot, d)).transpose()?;
            self.update_counts = [0; 2];
            if let Some(t) = &mut self.tracer {
                let (counts, host) = t.finish_update(&u.plan, &bounds, readback, &self.rebuild_policy)?;
                self.update_timings.extend(host);
                self.update_counts = [counts.refits, counts.rebuilds];
            }
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

    /// Replaces the frame ring by one of `slots` frames in flight (the
    /// viewer's); waits for the device.
    pub fn set_frames_in_flight(&mut self, ctx: &Context, slots: usize) -> Result<()> {
        unsafe { ctx.device.device_wait_idle() }
            .context("vkDeviceWaitIdle before replacing the frame ring")?;
        self.ring.destroy(ctx);
        self.ring = FrameRing::new(slots, "frame ring")?;
        self.pending = (0..slots).map(|_| Pending::default()).collect();
        self.open = None;
        Ok(())
    }

    /// After a completed frame (`done`, from `finish_frame`): the budget's
    /// selection for the next one (nothing without a budget, or when the
    /// frame measured nothing). With frames in flight the statistics are
    /// one frame older than the frame the selection applies to.
    pub fn finish_budget(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
        done: &Finished,
    ) -> Result<()> {
        let (Some(b), true) = (&settings.budget, self.config.is_some_and(|c| c.budget)) else {
            return Ok(());
        };
        let Some((words, traced)) = &done.budget else { return Ok(()) };
        let screen = budget::Screen { width: self.extent.width, height: self.extent.height };
        let timings = (!done.cold).then_some(&done.timings[..]);
        self.budget.after_frame(words, traced, scene, camera, screen, b, timings)
    }

    /// Makes the next frame under `budget` trace the effects `bits` (EFFECT_*
    /// bits per object) instead of what the heuristic chose.
    pub fn set_budget_selection(&mut self, budget: &budget::BudgetSettings, bits: Vec<u32>) {
        self.budget.set_selection(budget, bits);
    }

    /// The budget's last selection and what it was made from.
    pub fn budget_report(&self) -> Option<&budget::BudgetReport> {
        self.budget.last()
    }
}
