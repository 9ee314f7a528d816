//! The frame ring (src/vk/frame_ring.rs) with two frames in flight, under
//! synchronization validation: each frame uploads its own bytes into one
//! shared device buffer, the GPU reads and writes that buffer, and the frame
//! downloads the buffer and its timestamps into its slot. The host never
//! waits for the previous frame, only for the slot's own frame two ago, and
//! every frame's download must hold exactly that frame's values (the same
//! as with one slot, where the host waits for every frame).
use crate::common;

use ash::vk;
use gpu_allocator::MemoryLocation;
use hybrid_rt::vk::frame_ring::{Download, FrameRing, Source};
use hybrid_rt::vk::{Buffer, Context};

const SIZE: u64 = 256;
const FRAMES: u32 = 12;

/// What frame `i`'s download must hold: 0..64 and 64..80 uploaded, 80..128
/// untouched zeros, 128..192 filled on the GPU, 192..256 a GPU copy of 0..64.
fn expected(i: u32) -> Vec<u8> {
    let mut v = vec![0u8; SIZE as usize];
    for k in 0..64 {
        v[k] = (i as usize * 3 + k) as u8;
        v[192 + k] = v[k];
    }
    for k in 0..16 {
        v[64 + k] = (200 + i as usize + k) as u8;
    }
    for w in v[128..192].chunks_mut(4) {
        w.copy_from_slice(&(i * 7 + 1).to_le_bytes());
    }
    v
}

struct Frame {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// (frame index, buffer download, timestamp download) in flight.
    pending: Option<(u32, Download, Option<Download>)>,
}

/// Checks and returns the frame's downloaded buffer.
fn check(ring: &FrameRing, s: usize, (i, buf, ts): (u32, Download, Option<Download>)) -> Vec<u8> {
    let got = ring.read(s, buf).unwrap().to_vec();
    assert_eq!(got, expected(i), "frame {i} (slot {s}) downloaded another frame's bytes");
    if let Some(ts) = ts {
        let t: Vec<u64> = bytemuck::pod_collect_to_vec(ring.read(s, ts).unwrap());
        assert!(t[1] >= t[0] && t[1] > 0, "frame {i}: timestamps {t:?}");
    }
    got
}

/// Runs FRAMES frames through a ring of `slots`; returns every frame's
/// downloaded bytes and how many frames found the previous one still running.
fn run(ctx: &Context, slots: usize) -> (Vec<Vec<u8>>, u32) {
    let dev = &ctx.device;
    let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    let mut target =
        Buffer::new(ctx, "frame ring test target", SIZE, usage, MemoryLocation::GpuOnly).unwrap();
    let pool = ctx.caps.timestamps.then(|| {
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2 * slots as u32);
        let p = unsafe { dev.create_query_pool(&info, None) }.unwrap();
        ctx.name(p, "frame ring test timestamps");
        p
    });
    let mut ring = FrameRing::new(slots, "frame ring test").unwrap();
    let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
    let mut frames: Vec<Frame> = (0..slots)
        .map(|s| Frame {
            cmd: ctx.allocate_command_buffer(&format!("frame ring test {s}")).unwrap(),
            fence: unsafe { dev.create_fence(&signalled, None) }.unwrap(),
            pending: None,
        })
        .collect();
    let mut results = Vec::new();
    let mut overlapped = 0;
    for i in 0..FRAMES {
        let s = i as usize % slots;
        // Only this slot's own last frame is waited for.
        unsafe { dev.wait_for_fences(&[frames[s].fence], true, u64::MAX) }.unwrap();
        if let Some(p) = frames[s].pending.take() {
            results.push(check(&ring, s, p));
        }
        if slots > 1 && i > 0 {
            let prev = frames[(s + slots - 1) % slots].fence;
            overlapped += !unsafe { dev.get_fence_status(prev) }.unwrap() as u32;
        }
        ring.begin(s).unwrap();
        let e = expected(i);
        // A first write of the range is overwritten by the later one.
        ring.upload(s, &target, 0, &[0xee; 16]).unwrap();
        ring.upload(s, &target, 0, &e[..64]).unwrap();
        ring.upload(s, &target, 64, &e[64..80]).unwrap();
        let cmd = frames[s].cmd;
        ctx.begin_commands(cmd).unwrap();
        ring.record_uploads(ctx, cmd, s).unwrap();
        unsafe {
            if let Some(p) = pool {
                dev.cmd_reset_query_pool(cmd, p, 2 * s as u32, 2);
                dev.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, p, 2 * s as u32);
            }
            // Zero what no upload covers, then the frame's own GPU writes.
            dev.cmd_fill_buffer(cmd, target.raw, 80, 48, 0);
            dev.cmd_fill_buffer(cmd, target.raw, 128, 64, i * 7 + 1);
            let region = [vk::BufferCopy::default().src_offset(0).dst_offset(192).size(64)];
            dev.cmd_copy_buffer(cmd, target.raw, target.raw, &region);
            if let Some(p) = pool {
                dev.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, p, 2 * s as u32 + 1);
            }
        }
        let buf = ring.download(s, Source::Buffer { buffer: target.raw, offset: 0, size: SIZE }).unwrap();
        let ts = pool.map(|p| {
            ring.download(s, Source::Timestamps { pool: p, first: 2 * s as u32, count: 2 }).unwrap()
        });
        ring.record_downloads(ctx, cmd, s).unwrap();
        unsafe {
            dev.end_command_buffer(cmd).unwrap();
            dev.reset_fences(&[frames[s].fence]).unwrap();
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = vk::SubmitInfo2::default().command_buffer_infos(&cmds);
            dev.queue_submit2(ctx.queue, &[submit], frames[s].fence).unwrap();
        }
        frames[s].pending = Some((i, buf, ts));
    }
    unsafe { dev.device_wait_idle() }.unwrap();
    // The last frames, oldest first; read after the device is idle, so a
    // slot that shared another's readback would show the newer frame here.
    for k in 0..slots {
        let s = (FRAMES as usize + k) % slots;
        if let Some(p) = frames[s].pending.take() {
            results.push(check(&ring, s, p));
        }
    }
    ring.destroy(ctx);
    target.destroy(ctx);
    unsafe {
        for f in &frames {
            dev.destroy_fence(f.fence, None);
            dev.free_command_buffers(ctx.command_pool, &[f.cmd]);
        }
        if let Some(p) = pool {
            dev.destroy_query_pool(p, None);
        }
    }
    (results, overlapped)
}

#[test]
fn two_slots_in_flight_download_each_frames_own_values() {
    let ctx = crate::sync_validated_across_submits();
    let (one, _) = run(&ctx, 1);
    let (two, overlapped) = run(&ctx, 2);
    eprintln!("frame ring: {overlapped} of {} frames were staged while the previous one ran", FRAMES - 1);
    assert_eq!(one.len(), FRAMES as usize);
    assert_eq!(two, one, "two slots in flight downloaded other values than one slot");
    ctx.finish().expect("validation (synchronization included) clean");
}

#[test]
fn slots_are_checked() {
    let mut ring = FrameRing::new(2, "bad slot").unwrap();
    let e = ring.begin(2).unwrap_err().to_string();
    assert!(e.contains("slot 2 of 2"), "{e}");
    assert!(FrameRing::new(0, "none").is_err());
}

/// Staging after the slot's copies were recorded, or registering a download
/// after its copies were recorded, is an error (it would be lost silently).
#[test]
fn late_uploads_and_downloads_are_errors() {
    let ctx = common::sync_validated_context();
    let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    let mut target = Buffer::new(&ctx, "late test target", 64, usage, MemoryLocation::GpuOnly).unwrap();
    let mut ring = FrameRing::new(1, "late test").unwrap();
    let e = ring.upload(0, &target, 60, &[0; 8]).unwrap_err().to_string();
    assert!(e.contains("past the end of a 64-byte buffer"), "{e}");
    ctx.one_shot("late test", |cmd| {
        ring.upload(0, &target, 0, &[1; 8])?;
        ring.record_uploads(&ctx, cmd, 0)?;
        let e = ring.upload(0, &target, 0, &[2; 8]).unwrap_err().to_string();
        assert!(e.contains("after its slot's uploads were recorded"), "{e}");
        let d = ring.download(0, Source::Buffer { buffer: target.raw, offset: 0, size: 8 })?;
        ring.record_downloads(&ctx, cmd, 0)?;
        let e = ring.download(0, Source::Buffer { buffer: target.raw, offset: 0, size: 8 }).unwrap_err();
        assert!(e.to_string().contains("after its slot's downloads were recorded"), "{e}");
        Ok(d)
    })
    .map(|d| assert_eq!(ring.read(0, d).unwrap(), &[1; 8]))
    .unwrap();
    ring.begin(0).unwrap();
    ring.upload(0, &target, 0, &[3; 8]).expect("a new frame stages again");
    ring.destroy(&ctx);
    target.destroy(&ctx);
    ctx.finish().expect("validation clean");
}
