//! The per-frame loop: pacing between events (`about_to_wait`), one frame from fence wait to present
//! (`frame`), its recording with the present blit (`record`), the `--frames` end condition, GPU pass
//! times and screenshot readback.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;
use winit::event_loop::{ActiveEventLoop, ControlFlow};

use super::session::Viewer;
use super::swapchain::Acquired;
use super::{Flow, FRAMES_IN_FLIGHT};
use crate::render::frame::{Access, Use};
use crate::render::uses::TargetDesc;
use crate::render::{readback, Finished, FrameOutput};
use crate::vk::Buffer;

pub(super) struct FrameSlot {
    pub(super) cmd: vk::CommandBuffer,
    pub(super) fence: vk::Fence,
    pub(super) image_available: vk::Semaphore,
}

/// A frame copied to a host buffer, written to PNG once its fence is done.
pub(super) struct PendingShot {
    /// The frame slot whose fence it waits for.
    pub(super) slot: usize,
    pub(super) buffer: Buffer,
    pub(super) extent: vk::Extent2D,
    pub(super) path: PathBuf,
}

/// The acquired swapchain image as the present blit declares it (imported
/// into the frame's recorder each frame; never allocated).
static SWAPCHAIN: TargetDesc = TargetDesc::new("swapchain image", vk::Format::UNDEFINED);

impl Viewer {
    pub(super) fn about_to_wait(&mut self, el: &ActiveEventLoop) -> Result<Flow> {
        if let Some(t) = &mut self.resize_test {
            self.needs_recreate |= t.tick(&self.window, self.presented, self.presenter.extent, self.paused);
        }
        if self.paused {
            // Not every window system sends a resize when a window is
            // restored: look at the surface again now and then.
            el.set_control_flow(ControlFlow::wait_duration(Duration::from_millis(50)));
            if self.needs_recreate || self.last_recreate_try.elapsed() >= Duration::from_millis(50) {
                self.recreate()?;
            }
            if self.paused {
                return Ok(Flow::Continue);
            }
        }
        el.set_control_flow(ControlFlow::Poll);
        self.window.request_redraw();
        Ok(Flow::Continue)
    }

    /// The host's reads of frame slot `s`'s last frame (its fence is done; with two frames in flight it is
    /// two frames old): GPU pass times (with its scene update's), bad pixels, its screenshot. Empty when the
    /// slot held no frame.
    fn finish_slot(&mut self, s: usize) -> Result<Finished> {
        let done = self.renderer.finish_frame(s)?;
        if !done.timings.is_empty() {
            let mut t = done.timings.clone();
            if done.updated {
                t.extend(self.renderer.update.timings.iter().copied());
            }
            self.stats.gpu(&t);
        }
        if done.bad_pixels > 0 {
            self.stats.bad_pixels(done.bad_pixels);
        }
        self.finish_screenshots(Some(s))?;
        Ok(done)
    }

    /// Writes the pending screenshots of frame slot `slot` (None: all, the
    /// device is idle); their frames have completed.
    pub(super) fn finish_screenshots(&mut self, slot: Option<usize>) -> Result<()> {
        let (done, waiting) =
            std::mem::take(&mut self.shots).into_iter().partition(|p| slot.is_none_or(|s| p.slot == s));
        self.shots = waiting;
        let mut result = Ok(());
        for shot in done {
            let r = self.write_screenshot(shot);
            result = result.and(r);
        }
        result
    }

    fn write_screenshot(&mut self, mut shot: PendingShot) -> Result<()> {
        let r = (|| {
            let (w, h) = (shot.extent.width, shot.extent.height);
            let frame = FrameOutput::from_images(w, h, shot.buffer.read()?.to_vec(), Vec::new());
            frame.save_png(&shot.path)
        })();
        shot.buffer.destroy(&self.ctx);
        r?;
        self.shots_taken += 1;
        log::info!(
            "screenshot: wrote {} ({}x{})",
            shot.path.display(),
            shot.extent.width,
            shot.extent.height
        );
        Ok(())
    }

    /// Whether this frame is the last of `--frames`; errors when the window
    /// never gets back to the requested size.
    fn is_final_frame(&mut self) -> Result<bool> {
        let Some(n) = self.frames else { return Ok(false) };
        if self.presented + 1 < n {
            return Ok(false);
        }
        let test_busy = self.resize_test.as_ref().is_some_and(|t| !t.done());
        let size_ok = self.presenter.extent == self.requested;
        if !test_busy && size_ok {
            return Ok(true);
        }
        let since = *self.final_wait.get_or_insert_with(|| {
            log::info!(
                "frame {n} reached; waiting for {} before the last frame",
                if test_busy {
                    "the resize test to finish"
                } else {
                    "the window to return to its requested size"
                }
            );
            Instant::now()
        });
        if since.elapsed() > Duration::from_secs(20) {
            let e = self.presenter.extent;
            bail!(
                "the window stayed at {}x{} instead of the requested {}x{} for 20 s; no final frame",
                e.width,
                e.height,
                self.requested.width,
                self.requested.height
            );
        }
        Ok(false)
    }

    pub(super) fn frame(&mut self) -> Result<Flow> {
        if self.needs_recreate || !self.presenter.has_swapchain() {
            self.recreate()?;
        }
        if self.paused {
            return Ok(Flow::Continue);
        }
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f32();
        self.last_frame = now;
        let dev = &self.ctx.device;
        let s = self.slot;
        let FrameSlot { fence, image_available, .. } = self.slots[s];
        // This slot's previous frame (two ago) must be done with its command buffer, image-available
        // semaphore and ring slot. The other frame may still run: nothing below waits for it.
        unsafe { dev.wait_for_fences(&[fence], true, u64::MAX) }
            .context("waiting for a frame (device lost?)")?;
        let index = match self.presenter.acquire(image_available)? {
            Acquired::OutOfDate => {
                self.needs_recreate = true;
                return Ok(Flow::Continue);
            }
            Acquired::Image { index, suboptimal } => {
                self.needs_recreate |= suboptimal;
                index
            }
        };
        // Host writes for this frame go through ring slot s (copied at its command buffer's start), reads
        // come from slot s's last frame: the frame in flight is never touched.
        let done = self.finish_slot(s)?;
        // The budget selects this frame's objects from that frame's statistics (two frames old; after a
        // camera move the selection follows a frame later).
        let camera = self.controller.camera();
        self.renderer.finish_budget(&self.scene, &camera, &self.settings, &done)?;
        self.renderer.choices.visibility.after_frame(&done.timings);

        // --capture-frame N or F9: this frame, from its uniforms to its present, in a RenderDoc capture.
        let capture = self.ctx.wants_capture(self.presented) || std::mem::take(&mut self.capture_request);
        let what = format!("viewer frame {}", self.presented);
        if capture {
            self.ctx.start_capture(&what)?;
        }
        let drawn = self.draw(dt, s, index);
        if capture {
            // The frame's own error, if any, says more than the capture's.
            let ended = self.ctx.end_capture(&what);
            if drawn.is_ok() {
                ended?;
            }
        }
        let last = drawn?;

        let tick = self.stats.tick(Instant::now());
        if tick.title.is_some() {
            self.window.set_title(&self.title());
        }
        if let Some(line) = tick.log {
            log::info!("{line}");
        }
        if last {
            unsafe { self.ctx.device.device_wait_idle() }.context("vkDeviceWaitIdle")?;
            // Both slots' frames, oldest first (`self.slot` is the next).
            for k in 0..FRAMES_IN_FLIGHT {
                self.finish_slot((self.slot + k) % FRAMES_IN_FLIGHT)?;
            }
            return Ok(Flow::Exit);
        }
        Ok(Flow::Continue)
    }

    /// Updates camera and animation, records, submits and presents frame
    /// slot `s` into swapchain image `index`; true when it was the last.
    fn draw(&mut self, dt: f32, s: usize, index: u32) -> Result<bool> {
        let FrameSlot { cmd, fence, image_available } = self.slots[s];
        self.controller.update(dt);
        // Eye adaptation follows the wall clock (the first frame converges).
        self.renderer.choices.adapt_dt = (self.presented > 0).then_some(dt);
        if let Some((i, clock, paused)) = &mut self.animation {
            if !*paused {
                // Wall-clock playback unless a fixed step was asked for (the
                // first frame shows the start time).
                *clock += match self.fixed_fps {
                    Some(fps) if self.presented > 0 => 1.0 / fps,
                    Some(_) => 0.0,
                    None => dt,
                };
                self.scene_dirty = true;
            }
            if self.scene_dirty {
                self.scene.animate(*i, *clock);
            }
        }
        let camera = self.controller.camera();
        self.renderer.begin_frame(s)?;
        self.renderer.prepare(&self.ctx, &self.scene, &camera, &self.settings)?;
        // The scene update (skinning, refit, top level) goes into this
        // frame's command buffer, for every backend: no wait for it here.
        let update_in_frame = std::mem::take(&mut self.scene_dirty);

        let last = self.is_final_frame()?;
        let shot_path =
            (if last { self.screenshot.clone() } else { None }).or_else(|| self.shot_request.take());
        let shot_buffer = match &shot_path {
            Some(_) => {
                let e = self.renderer.extent();
                Some(Buffer::new(
                    &self.ctx,
                    "screenshot readback",
                    e.width as u64 * e.height as u64 * 4,
                    vk::BufferUsageFlags::TRANSFER_DST,
                    MemoryLocation::GpuToCpu,
                )?)
            }
            None => None,
        };
        let recorded = self.record(cmd, index, update_in_frame, shot_buffer.as_ref());
        if let (Some(buffer), Some(path)) = (shot_buffer, shot_path) {
            self.shots.push(PendingShot { slot: s, buffer, extent: self.renderer.extent(), path });
        }
        recorded?;

        let dev = &self.ctx.device;
        unsafe { dev.reset_fences(&[fence]) }?;
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(image_available)
            .stage_mask(vk::PipelineStageFlags2::BLIT)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.presenter.render_finished[index as usize])
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals);
        unsafe { dev.queue_submit2(self.ctx.queue, &[submit], fence) }
            .context("vkQueueSubmit2 (device lost?)")?;
        self.needs_recreate |= self.presenter.present(self.ctx.queue, index)?;
        self.presented += 1;
        self.slot = (s + 1) % FRAMES_IN_FLIGHT;
        self.stats.frame_presented();

        Ok(last)
    }

    /// The frame's commands: the scene update when `update`, the renderer's passes, then the blit of the
    /// tone-mapped image into swapchain image `index` (and a screenshot's readback), ending in PRESENT_SRC.
    fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        index: u32,
        update: bool,
        shot: Option<&Buffer>,
    ) -> Result<()> {
        let ctx = &self.ctx;
        ctx.begin_commands(cmd)?;
        if update {
            self.renderer.record_scene_update(ctx, cmd, &self.scene)?;
        }
        let image = self.presenter.images[index as usize];
        let dst = self.presenter.extent;
        // The frame's final LDR image: anti-aliased, or tone mapping's.
        let final_ldr = self.renderer.output_ldr()?;
        let uses =
            [Use::image(final_ldr, Access::TransferRead), Use::image(&SWAPCHAIN, Access::TransferWrite)];
        self.renderer.record_with(ctx, cmd, |rec, t| {
            let ldr = t.get(final_ldr).context("no displayable output")?;
            // Imported, so its barriers are derived like a target's (the first waits for the acquire
            // semaphore's stage, the last hands it to presentation).
            rec.import(&SWAPCHAIN, image, vk::ImageAspectFlags::COLOR);
            rec.pass("present blit", vk::PipelineStageFlags2::NONE, &uses, |cmd| {
                let src = t.extent;
                let layers = vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .layer_count(1);
                let corner = |e: vk::Extent2D| vk::Offset3D { x: e.width as i32, y: e.height as i32, z: 1 };
                let region = [vk::ImageBlit::default()
                    .src_subresource(layers)
                    .src_offsets([vk::Offset3D::default(), corner(src)])
                    .dst_subresource(layers)
                    .dst_offsets([vk::Offset3D::default(), corner(dst)])];
                let filter = if src == dst { vk::Filter::NEAREST } else { vk::Filter::LINEAR };
                unsafe {
                    ctx.device.cmd_blit_image(
                        cmd,
                        ldr.raw,
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &region,
                        filter,
                    )
                };
                Ok(())
            })?;
            if let Some(buf) = shot {
                readback::record(ctx, rec, t, &[(final_ldr, buf.raw)])?;
            }
            rec.transition(&[Use::image(&SWAPCHAIN, Access::Present)])
        })?;
        unsafe { ctx.device.end_command_buffer(cmd)? };
        Ok(())
    }
}
