//! What the host reads of a finished frame, after its fence: the
//! readback buffers, the budget's statistics, auto exposure's state and the
//! bad-pixel counter. One place for them, since frames in flight (issue 19
//! item 7, vk/frame_ring.rs) will move each of these reads to its slot.

use anyhow::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{budget, tone, ExposureState, RenderSettings, Renderer};
use crate::gpu::shared::RAY_COUNTER_BAD_PIXELS;
use crate::scene::{Camera, Scene};
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

impl Renderer {
    /// After a completed frame (its GPU pass times `timings`): the budget's
    /// selection for the next one (nothing without a budget).
    pub fn finish_budget(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
        timings: &[(&'static str, f64)],
    ) -> Result<()> {
        let (Some(b), true) = (&settings.budget, self.config.is_some_and(|c| c.budget)) else {
            return Ok(());
        };
        let screen = budget::Screen { width: self.extent.width, height: self.extent.height };
        let timings = (!self.recorded_cold).then_some(timings);
        self.budget.after_frame(&self.gpu, scene, camera, screen, b, timings)
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

    /// What auto exposure measured in the last completed frame (None when
    /// the frame measures no luminance).
    pub fn exposure_state(&self) -> Result<Option<ExposureState>> {
        if !self.config.is_some_and(|c| c.luminance) {
            return Ok(None);
        }
        let bytes = &self.gpu.exposure.read()?[..tone::EXPOSURE_STATE_BYTES];
        Ok(Some(bytemuck::pod_read_unaligned(bytes)))
    }

    /// Reads and clears the bad-pixel counter (the viewer, after its frame's fence).
    pub fn take_bad_pixels(&mut self) -> Result<u32> {
        let at = RAY_COUNTER_BAD_PIXELS as usize * 4;
        let n = bytemuck::pod_read_unaligned(&self.gpu.ray_counters.read()?[at..at + 4]);
        self.gpu.ray_counters.write(at, &[0u8; 4])?;
        Ok(n)
    }
}
