//! Frames in flight through the renderer (issue 19 item 7): the viewer's
//! sequence without a window. Two frame slots, each with its command buffer
//! and fence; a frame waits only for its own slot's frame two ago, reads
//! that frame's results, stages its host writes (uniforms, instances,
//! joints, the tracer's top level) in the renderer's ring slot and records
//! its scene update and passes while the other frame may still run. A
//! skinned animation plays; every frame must equal the same frame rendered
//! with a wait after every frame (`update_scene` + `render`), some frame's
//! whole host work must finish while the previous frame still runs, and
//! synchronization validation (across submissions too) must stay clean.
use crate::common;

use ash::vk;
use gpu_allocator::MemoryLocation;
use hybrid_rt::image_diff::diff_stats;
use hybrid_rt::render::readback;
use hybrid_rt::render::{RenderSettings, Renderer};
use hybrid_rt::scene::animation::find_animation;
use hybrid_rt::scene::Scene;
use hybrid_rt::vk::{Buffer, Context};

const W: u32 = 160;
const H: u32 = 90;
const FRAMES: usize = 8;
const SLOTS: usize = 2;

fn time(i: usize) -> f32 {
    0.3 + i as f32 * 0.1
}

/// Renders FRAMES animated frames with SLOTS in flight; returns every
/// frame's final LDR image and how many frames were recorded whole (the
/// renderer's begin, prepare and record included) while the previous one
/// still ran.
fn in_flight(ctx: &Context, loaded: &Scene, anim: usize, settings: &RenderSettings) -> (Vec<Vec<u8>>, usize) {
    let dev = &ctx.device;
    let camera = loaded.cameras[0].clone();
    let mut scene = loaded.clone();
    scene.animate(anim, time(0));
    let mut r = Renderer::new(ctx, &scene, vk::Extent2D { width: W, height: H }).unwrap();
    r.set_frames_in_flight(ctx, SLOTS).unwrap();
    let signaled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
    let slots: Vec<(vk::CommandBuffer, vk::Fence, Buffer)> = (0..SLOTS)
        .map(|s| {
            let cmd = ctx.allocate_command_buffer(&format!("frame slot {s}")).unwrap();
            let fence = unsafe { dev.create_fence(&signaled, None) }.unwrap();
            let bytes = W as u64 * H as u64 * 4;
            let usage = vk::BufferUsageFlags::TRANSFER_DST;
            let readback = Buffer::new(ctx, "test readback", bytes, usage, MemoryLocation::GpuToCpu).unwrap();
            (cmd, fence, readback)
        })
        .collect();
    let mut overlapped = 0;
    let mut frames = vec![Vec::new(); FRAMES];
    for i in 0..FRAMES {
        let s = i % SLOTS;
        let (cmd, fence, ref readback) = slots[s];
        unsafe { dev.wait_for_fences(&[fence], true, u64::MAX) }.unwrap();
        if i >= SLOTS {
            frames[i - SLOTS] = readback.read().unwrap().to_vec();
        }
        r.finish_frame(s).unwrap();
        r.begin_frame(s).unwrap();
        scene.animate(anim, time(i));
        r.prepare(ctx, &scene, &camera, settings).unwrap();
        ctx.begin_commands(cmd).unwrap();
        r.record_scene_update(ctx, cmd, &scene).unwrap();
        let copies = [(r.output_ldr().unwrap(), readback.raw)];
        r.record_with(ctx, cmd, |rec, t| readback::record(ctx, rec, t, &copies)).unwrap();
        // The previous frame still running now shows that nothing above waited for it.
        let other = slots[(s + SLOTS - 1) % SLOTS].1;
        overlapped += (i > 0 && !unsafe { dev.get_fence_status(other) }.unwrap()) as usize;
        unsafe {
            dev.end_command_buffer(cmd).unwrap();
            dev.reset_fences(&[fence]).unwrap();
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = vk::SubmitInfo2::default().command_buffer_infos(&cmds);
            dev.queue_submit2(ctx.queue, &[submit], fence).unwrap();
        }
    }
    unsafe { dev.device_wait_idle() }.unwrap();
    for k in 0..SLOTS {
        r.finish_frame((FRAMES + k) % SLOTS).unwrap();
    }
    for (i, frame) in frames.iter_mut().enumerate().skip(FRAMES - SLOTS) {
        *frame = slots[i % SLOTS].2.read().unwrap().to_vec();
    }
    for (cmd, fence, mut readback) in slots {
        unsafe {
            dev.destroy_fence(fence, None);
            dev.free_command_buffers(ctx.command_pool, &[cmd]);
        }
        readback.destroy(ctx);
    }
    r.destroy(ctx);
    (frames, overlapped)
}

/// The same frames with the host waiting for each one.
fn waited(ctx: &Context, loaded: &Scene, anim: usize, settings: &RenderSettings) -> Vec<Vec<u8>> {
    let camera = loaded.cameras[0].clone();
    let mut scene = loaded.clone();
    scene.animate(anim, time(0));
    let mut r = Renderer::new(ctx, &scene, vk::Extent2D { width: W, height: H }).unwrap();
    let mut frames = Vec::new();
    for i in 0..FRAMES {
        scene.animate(anim, time(i));
        r.update_scene(ctx, &scene).unwrap();
        frames.push(r.render(ctx, &scene, &camera, settings).unwrap().ldr);
    }
    r.destroy(ctx);
    frames
}

#[test]
fn two_frames_in_flight_render_the_animation_like_waiting_frames() {
    let loaded = Scene::load(&common::shared_asset("gltf/CesiumMan/glTF/CesiumMan.gltf")).unwrap();
    let anim = find_animation(&loaded, "0").unwrap();
    let ctx = crate::sync_validated_across_submits();
    for backend in common::BACKENDS {
        let settings = RenderSettings { backend, ..Default::default() };
        let (flight, overlapped) = in_flight(&ctx, &loaded, anim, &settings);
        let reference = waited(&ctx, &loaded, anim, &settings);
        eprintln!("{backend:?}: {overlapped} of {} frames recorded while the previous one ran", FRAMES - 1);
        // A frame takes lavapipe tens of ms and its recording about one: a renderer that waited for
        // the GPU anywhere in a frame's host work would show no overlap at all.
        assert!(overlapped > 0, "{backend:?}: no frame was recorded while the previous one ran");
        for (i, (f, w)) in flight.iter().zip(&reference).enumerate() {
            let (max, frac) = diff_stats(f, w, 4, 0);
            assert!(
                max <= 2 && frac < 0.001,
                "{backend:?} frame {i}: in flight vs waited: max {max}, {frac}"
            );
        }
    }
    ctx.finish().expect("validation (synchronization included) clean");
}
