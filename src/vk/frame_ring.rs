//! Per-slot host staging for frames in flight. With N in flight the host prepares frame N+1 while the
//! GPU still runs frame N, so the host may not write in place what frame N reads, nor may frame N+1
//! overwrite what the host has yet to read of frame N. The ring keeps the device buffers (and their
//! descriptor sets) single and moves every host access to a per-slot staging range:
//!
//! - uploads: staged into slot s; at the START of frame s's GPU work `record_uploads` copies them into
//!   the device buffers, between a barrier ordering the copies after every earlier submission's reads
//!   and writes (WAR / WAW on the single device buffers) and one making them visible to the frame.
//! - downloads: at the END of frame s's GPU work `record_downloads` copies buffer ranges (or timestamp
//!   query results) into slot s's readback range; the host reads them (`read`) after slot s's fence.
//!
//! The host touches slot s only after its previous frame's fence (N frames ago), which makes per-slot
//! staging safe to rewrite and grow. The ring knows nothing of what the bytes mean.

use anyhow::{ensure, Context as _, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{copy_to_host_barrier, memory_barrier, Buffer, Context};

/// Where a download comes from.
#[derive(Clone, Copy, Debug)]
pub enum Source {
    /// `size` bytes of a buffer (TRANSFER_SRC usage) from `offset`.
    Buffer { buffer: vk::Buffer, offset: u64, size: u64 },
    /// `count` 64-bit timestamp results from query `first` of `pool`; the
    /// copy waits for them on the GPU (no host wait).
    Timestamps { pool: vk::QueryPool, first: u32, count: u32 },
}

impl Source {
    fn size(&self) -> u64 {
        match *self {
            Source::Buffer { size, .. } => size,
            Source::Timestamps { count, .. } => count as u64 * 8,
        }
    }
}

/// A download registered for a slot; `read` returns its bytes once the slot's fence has signalled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Download(usize);

struct Upload {
    dst: vk::Buffer,
    dst_offset: u64,
    src_offset: u64,
    size: u64,
}

#[derive(Default)]
struct Slot {
    /// Staged bytes, copied into `staging` when the uploads are recorded.
    bytes: Vec<u8>,
    uploads: Vec<Upload>,
    staging: Option<Buffer>,
    downloads: Vec<(Source, u64)>,
    readback: Option<Buffer>,
    /// The uploads were recorded: a later upload would never be copied.
    uploads_recorded: bool,
    /// The downloads were recorded and may be read after the fence.
    recorded: bool,
}

pub struct FrameRing {
    slots: Vec<Slot>,
    name: String,
}

/// Copies land at 16-byte aligned staging offsets (the strictest alignment
/// a copy region of our buffers needs; vkCmdCopyQueryPoolResults needs 8).
const ALIGN: u64 = 16;

fn align(n: u64) -> u64 {
    n.div_ceil(ALIGN) * ALIGN
}

impl FrameRing {
    /// A ring of `slots` (>= 1) frames in flight; `name` prefixes the debug names of its staging buffers.
    pub fn new(slots: usize, name: &str) -> Result<FrameRing> {
        ensure!(slots >= 1, "a frame ring needs at least one slot");
        Ok(FrameRing { slots: (0..slots).map(|_| Slot::default()).collect(), name: name.to_string() })
    }

    pub fn slots(&self) -> usize {
        self.slots.len()
    }

    fn slot(&mut self, s: usize) -> Result<&mut Slot> {
        let n = self.slots.len();
        self.slots.get_mut(s).with_context(|| format!("frame ring slot {s} of {n}"))
    }

    /// Starts a new frame in slot `s`, forgetting its last frame's uploads and downloads. Call after slot
    /// `s`'s previous fence has signalled (and its downloads were read).
    pub fn begin(&mut self, s: usize) -> Result<()> {
        let slot = self.slot(s)?;
        slot.bytes.clear();
        slot.uploads.clear();
        slot.downloads.clear();
        slot.uploads_recorded = false;
        slot.recorded = false;
        Ok(())
    }

    /// Stages `data` for `dst` (a device buffer with TRANSFER_DST usage) at `offset`, copied in
    /// `record_uploads` of the same slot. A later upload to an overlapping range wins.
    pub fn upload(&mut self, s: usize, dst: &Buffer, offset: u64, data: &[u8]) -> Result<()> {
        ensure!(
            offset + data.len() as u64 <= dst.size,
            "frame ring: upload of {} bytes at {offset} past the end of a {}-byte buffer",
            data.len(),
            dst.size
        );
        if data.is_empty() {
            return Ok(());
        }
        let slot = self.slot(s)?;
        ensure!(!slot.uploads_recorded, "frame ring: upload staged after its slot's uploads were recorded");
        let src_offset = align(slot.bytes.len() as u64);
        slot.bytes.resize(src_offset as usize, 0);
        slot.bytes.extend_from_slice(data);
        slot.uploads.push(Upload { dst: dst.raw, dst_offset: offset, src_offset, size: data.len() as u64 });
        Ok(())
    }

    /// Records slot `s`'s staged copies; put them first in the frame's GPU
    /// work (before any command that reads the destination buffers).
    pub fn record_uploads(&mut self, ctx: &Context, cmd: vk::CommandBuffer, s: usize) -> Result<()> {
        let name = format!("{} uploads {s}", self.name);
        let slot = self.slot(s)?;
        slot.uploads_recorded = true;
        ctx.begin_label(cmd, &name, super::timer::label_color("frame ring uploads"));
        // The frame boundary, recorded even without uploads: every earlier submission (the previous frame,
        // maybe still running) finishes with the single device buffers and targets before this frame's
        // copies and passes touch them.
        memory_barrier(
            ctx,
            cmd,
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_WRITE),
            (
                vk::PipelineStageFlags2::ALL_COMMANDS,
                vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
            ),
        );
        if slot.uploads.is_empty() {
            ctx.end_label(cmd);
            return Ok(());
        }
        let need = slot.bytes.len() as u64;
        let usage = vk::BufferUsageFlags::TRANSFER_SRC;
        let staging = grow(ctx, &mut slot.staging, need, &name, usage, MemoryLocation::CpuToGpu)?;
        staging.write(0, &slot.bytes)?;
        // Copies between two barriers are unordered: a copy overlapping an
        // earlier one of the batch waits for it, so the later upload wins.
        let mut since_barrier: Vec<&Upload> = Vec::new();
        for u in &slot.uploads {
            let overlaps = |o: &&Upload| {
                o.dst == u.dst && o.dst_offset < u.dst_offset + u.size && u.dst_offset < o.dst_offset + o.size
            };
            if since_barrier.iter().any(overlaps) {
                let copy_write = (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE);
                memory_barrier(ctx, cmd, copy_write, copy_write);
                since_barrier.clear();
            }
            since_barrier.push(u);
            let region =
                [vk::BufferCopy::default().src_offset(u.src_offset).dst_offset(u.dst_offset).size(u.size)];
            unsafe { ctx.device.cmd_copy_buffer(cmd, staging.raw, u.dst, &region) };
        }
        memory_barrier(
            ctx,
            cmd,
            (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
            (
                vk::PipelineStageFlags2::ALL_COMMANDS,
                vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
            ),
        );
        ctx.end_label(cmd);
        Ok(())
    }

    /// Registers a download for the end of slot `s`'s frame.
    pub fn download(&mut self, s: usize, source: Source) -> Result<Download> {
        let slot = self.slot(s)?;
        ensure!(!slot.recorded, "frame ring: download registered after its slot's downloads were recorded");
        let at = slot.downloads.last().map_or(0, |(src, at)| align(at + src.size()));
        slot.downloads.push((source, at));
        Ok(Download(slot.downloads.len() - 1))
    }

    /// Records slot `s`'s downloads; put them last in the frame's GPU work.
    pub fn record_downloads(&mut self, ctx: &Context, cmd: vk::CommandBuffer, s: usize) -> Result<()> {
        let name = format!("{} readback {s}", self.name);
        let slot = self.slot(s)?;
        slot.recorded = true;
        let Some(&(last, at)) = slot.downloads.last() else { return Ok(()) };
        let need = at + last.size();
        let readback = grow(
            ctx,
            &mut slot.readback,
            need,
            &name,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        ctx.begin_label(cmd, &name, super::timer::label_color("frame ring readback"));
        // Everything the frame wrote is complete before it is copied.
        memory_barrier(
            ctx,
            cmd,
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_WRITE),
            (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ),
        );
        for &(src, at) in &slot.downloads {
            match src {
                Source::Buffer { buffer, offset, size } => {
                    let region = [vk::BufferCopy::default().src_offset(offset).dst_offset(at).size(size)];
                    unsafe { ctx.device.cmd_copy_buffer(cmd, buffer, readback.raw, &region) };
                }
                Source::Timestamps { pool, first, count } => unsafe {
                    ctx.device.cmd_copy_query_pool_results(
                        cmd,
                        pool,
                        first,
                        count,
                        readback.raw,
                        at,
                        8,
                        vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                    )
                },
            }
        }
        copy_to_host_barrier(ctx, cmd);
        ctx.end_label(cmd);
        Ok(())
    }

    /// The bytes of download `d` of slot `s`; call after the fence of the
    /// submission that held `record_downloads(s)`.
    pub fn read(&self, s: usize, d: Download) -> Result<&[u8]> {
        let slot = self.slots.get(s).with_context(|| format!("frame ring slot {s}"))?;
        ensure!(slot.recorded, "frame ring: slot {s}'s downloads were never recorded");
        let &(src, at) = slot.downloads.get(d.0).context("frame ring: unknown download")?;
        let bytes = slot.readback.as_ref().context("frame ring: no readback buffer")?.read()?;
        Ok(&bytes[at as usize..(at + src.size()) as usize])
    }

    /// Frees the staging memory (after the device is idle).
    pub fn destroy(&mut self, ctx: &Context) {
        for slot in &mut self.slots {
            for b in [&mut slot.staging, &mut slot.readback].into_iter().flatten() {
                b.destroy(ctx);
            }
            slot.staging = None;
            slot.readback = None;
        }
    }
}

/// `buf`, replaced by a larger one (twice the need, to grow rarely) when
/// smaller than `need`. Only called for a slot whose last frame completed.
fn grow<'a>(
    ctx: &Context,
    buf: &'a mut Option<Buffer>,
    need: u64,
    name: &str,
    usage: vk::BufferUsageFlags,
    location: MemoryLocation,
) -> Result<&'a mut Buffer> {
    if buf.as_ref().is_some_and(|b| b.size < need) {
        if let Some(mut old) = buf.take() {
            old.destroy(ctx);
        }
    }
    if buf.is_none() {
        *buf = Some(Buffer::new(ctx, name, (need * 2).max(256), usage, location)?);
    }
    buf.as_mut().context("frame ring staging")
}

/// One frame's host writes, staged into its ring slot and copied into the device buffers at the frame's
/// start (`FrameRing::record_uploads`): the host never writes memory a frame in flight reads.
pub struct Uploads<'a> {
    pub ring: &'a mut FrameRing,
    pub slot: usize,
}

impl Uploads<'_> {
    /// Stages `data` for `dst` (TRANSFER_DST usage) at byte `offset`.
    pub fn write(&mut self, dst: &Buffer, offset: usize, data: &[u8]) -> Result<()> {
        self.ring.upload(self.slot, dst, offset as u64, data)
    }
}

/// Writes made outside any frame (loading, a rebuild after an idle wait):
/// `f` stages them, one submission copies them, and this waits for it.
pub fn upload_now(ctx: &Context, name: &str, f: impl FnOnce(&mut Uploads) -> Result<()>) -> Result<()> {
    let mut ring = FrameRing::new(1, name)?;
    let r = (|| {
        ring.begin(0)?;
        f(&mut Uploads { ring: &mut ring, slot: 0 })?;
        ctx.one_shot(name, |cmd| ring.record_uploads(ctx, cmd, 0))
    })();
    ring.destroy(ctx);
    r
}
