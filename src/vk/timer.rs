//! Per-pass GPU timing with timestamp queries (the pass layer, render/frame.rs, opens and closes a slot
//! around every pass).

use anyhow::Result;
use ash::vk;

use super::frame_ring::{Download, FrameRing, Source};
use super::Context;

/// Timestamps for up to `capacity` passes per frame.
pub struct GpuTimer {
    pool: vk::QueryPool,
    capacity: u32,
    names: Vec<&'static str>,
    period_ns: f64,
    enabled: bool,
}

impl GpuTimer {
    /// A timer that owns nothing yet (placeholder until `new` succeeds).
    pub fn empty() -> GpuTimer {
        GpuTimer {
            pool: vk::QueryPool::null(),
            capacity: 0,
            names: Vec::new(),
            period_ns: 1.0,
            enabled: false,
        }
    }

    pub fn new(ctx: &Context, capacity: u32) -> Result<GpuTimer> {
        let enabled = ctx.caps.timestamps;
        let pool = if enabled {
            let p = unsafe {
                ctx.device.create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::TIMESTAMP)
                        .query_count(capacity * 2),
                    None,
                )?
            };
            ctx.name(p, "pass timestamps");
            p
        } else {
            log::warn!("device has no timestamp queries: pass times unavailable");
            vk::QueryPool::null()
        };
        Ok(GpuTimer {
            pool,
            capacity,
            names: Vec::new(),
            period_ns: ctx.caps.timestamp_period_ns as f64,
            enabled,
        })
    }

    /// Resets the queries; call at the start of a frame's command buffer.
    pub fn begin_frame(&mut self, ctx: &Context, cmd: vk::CommandBuffer) {
        self.names.clear();
        if self.enabled {
            unsafe { ctx.device.cmd_reset_query_pool(cmd, self.pool, 0, self.capacity * 2) };
        }
    }

    fn write(&self, ctx: &Context, cmd: vk::CommandBuffer, query: u32, stage: vk::PipelineStageFlags2) {
        if self.enabled {
            unsafe { ctx.device.cmd_write_timestamp2(cmd, stage, self.pool, query) };
        }
    }

    /// Registers the frame's timestamps as a download of ring slot `slot`, copied on the GPU at the frame's
    /// end (the host never reads the pool a later frame resets); `Readback::ms` turns them into times.
    pub fn download(&self, ring: &mut FrameRing, slot: usize) -> Result<Readback> {
        let count = self.names.len() as u32 * 2;
        let download = match self.enabled && count > 0 {
            true => Some(ring.download(slot, Source::Timestamps { pool: self.pool, first: 0, count })?),
            false => None,
        };
        Ok(Readback { names: self.names.clone(), download, period_ns: self.period_ns })
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if self.pool != vk::QueryPool::null() {
            unsafe { ctx.device.destroy_query_pool(self.pool, None) };
            self.pool = vk::QueryPool::null();
        }
    }
}

impl GpuTimer {
    /// Starts timing pass `name`; returns its slot, or None when the pool is full.
    pub fn begin(&mut self, ctx: &Context, cmd: vk::CommandBuffer, name: &'static str) -> Option<u32> {
        let slot = self.names.len() as u32;
        if slot >= self.capacity {
            return None;
        }
        self.names.push(name);
        self.write(ctx, cmd, 2 * slot, vk::PipelineStageFlags2::TOP_OF_PIPE);
        Some(slot)
    }

    /// Ends the timing of `slot` once the work recorded before has finished.
    pub fn end(&mut self, ctx: &Context, cmd: vk::CommandBuffer, slot: u32) {
        self.write(ctx, cmd, 2 * slot + 1, vk::PipelineStageFlags2::BOTTOM_OF_PIPE);
    }
}

/// A frame's pass names and where its timestamps land in its ring slot.
pub struct Readback {
    names: Vec<&'static str>,
    download: Option<Download>,
    period_ns: f64,
}

impl Readback {
    /// Milliseconds per pass, after the fence of the slot's frame (NaN without timestamps).
    pub fn ms(&self, ring: &FrameRing, slot: usize) -> Result<Vec<(&'static str, f64)>> {
        let Some(d) = self.download else {
            return Ok(self.names.iter().map(|n| (*n, f64::NAN)).collect());
        };
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(ring.read(slot, d)?);
        Ok(self.names.iter().zip(ticks.chunks_exact(2)).map(|(n, t)| (*n, ms(t, self.period_ns))).collect())
    }
}

fn ms(ticks: &[u64], period_ns: f64) -> f64 {
    ticks[1].wrapping_sub(ticks[0]) as f64 * period_ns * 1e-6
}

/// A stable colour per pass name so captures are easy to scan.
pub fn label_color(name: &str) -> [f32; 4] {
    let h = name.bytes().fold(2166136261u32, |h, b| (h ^ b as u32).wrapping_mul(16777619));
    [(h & 0xff) as f32 / 255.0, ((h >> 8) & 0xff) as f32 / 255.0, ((h >> 16) & 0xff) as f32 / 255.0, 1.0]
}
