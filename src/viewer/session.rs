//! The viewer's state (`Viewer`) and its lifetime: building it (scene, window, Vulkan context, renderer,
//! presenter, frame slots), recreating the swapchain on resize, and tearing it down in order.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context as _, Result};
use ash::vk;
use raw_window_handle::HasDisplayHandle;
use winit::dpi::PhysicalSize;
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::ModifiersState;
use winit::window::Window;

use super::camera_controller::CameraController;
use super::frame_loop::{FrameSlot, PendingShot};
use super::resize_test::ResizeTest;
use super::stats::FrameStats;
use super::swapchain::Presenter;
use super::{NoDisplay, ViewerOptions, FRAMES_IN_FLIGHT};
use crate::app::{CameraChoice, RenderJob};
use crate::render::budget::BudgetSettings;
use crate::render::{RenderSettings, Renderer};
use crate::scene::Scene;
use crate::vk::{built, Context, ContextOptions, RenderDocUse};

pub(super) struct Viewer {
    pub(super) renderer: Renderer,
    pub(super) presenter: Presenter,
    pub(super) slots: Vec<FrameSlot>,
    pub(super) slot: usize,
    /// Screenshots copied by frames still in flight.
    pub(super) shots: Vec<PendingShot>,
    pub(super) shot_request: Option<PathBuf>,
    pub(super) shots_taken: u32,
    /// F9: capture the next frame with RenderDoc.
    pub(super) capture_request: bool,
    pub(super) scene: Scene,
    /// Animation being played: (index, clock in seconds, paused).
    pub(super) animation: Option<(usize, f32, bool)>,
    /// The scene moved since the last frame: the renderer must update.
    pub(super) scene_dirty: bool,
    pub(super) controller: CameraController,
    pub(super) settings: RenderSettings,
    /// The stickiness and fallback F8 turns the budget on with: the command line's, then the keys' last.
    pub(super) budget_keys: BudgetSettings,
    pub(super) stats: FrameStats,
    pub(super) needs_recreate: bool,
    pub(super) paused: bool,
    pub(super) last_recreate_try: Instant,
    pub(super) last_frame: Instant,
    pub(super) presented: u64,
    pub(super) cursor: Option<(f64, f64)>,
    pub(super) modifiers: ModifiersState,
    pub(super) requested: vk::Extent2D,
    pub(super) frames: Option<u64>,
    pub(super) fixed_fps: Option<f32>,
    pub(super) screenshot: Option<PathBuf>,
    pub(super) final_wait: Option<Instant>,
    pub(super) resize_test: Option<ResizeTest>,
    pub(super) scene_name: String,
    // Dropped after everything above is destroyed (see Drop): the context,
    // then the window the surface belonged to.
    pub(super) ctx: Context,
    pub(super) window: Window,
}

fn validate_extent(job: &RenderJob) -> Result<vk::Extent2D> {
    if job.width == 0 || job.height == 0 || job.width > 16384 || job.height > 16384 {
        bail!("resolution {}x{} out of range (1..=16384)", job.width, job.height);
    }
    Ok(vk::Extent2D { width: job.width, height: job.height })
}

impl Viewer {
    pub(super) fn new(el: &ActiveEventLoop, opts: &ViewerOptions) -> Result<Viewer> {
        let job = &opts.job;
        let requested = validate_extent(job)?;
        let _load = crate::progress::begin();
        let mut scene = crate::app::load_scene(job)?;
        let animation = match &job.animation {
            Some(a) => {
                let i = crate::scene::animation::find_animation(&scene, a)?;
                scene.animate(i, job.time);
                Some((i, job.time, false))
            }
            None => None,
        };
        let camera = job.camera.resolve(&scene)?;
        // The scene's exposure resolved once: the exposure and tone keys start from what is shown.
        let (exposure, tone) = job.settings.exposure_for(scene.environment.exposure);
        let start_index = match job.camera {
            CameraChoice::First => Some(0),
            CameraChoice::Index(i) => Some(i),
            CameraChoice::LookAt { .. } => None,
        };
        let scene_name = job.scene.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();

        let attrs = Window::default_attributes()
            .with_title(format!("hybrid-rt - {scene_name}"))
            .with_inner_size(PhysicalSize::new(requested.width, requested.height))
            .with_resizable(true);
        let window = el.create_window(attrs).map_err(|e| NoDisplay(format!("creating the window: {e}")))?;
        let display = window.display_handle().context("display handle")?.as_raw();
        let surface_extensions = ash_window::enumerate_required_extensions(display)
            .context("this window system has no Vulkan surface extension")?
            .to_vec();
        let g = &opts.gpu;
        let ctx = Context::new(&ContextOptions {
            gpu: g.clone(),
            surface_extensions,
            swapchain: true,
            // The capture key works whenever the viewer runs under RenderDoc.
            renderdoc: if g.capture_frame.is_some() {
                RenderDocUse::Required
            } else {
                RenderDocUse::IfRunning
            },
        })?;
        // The renderer stages host writes and reads results per frame slot,
        // so a frame is recorded while the previous one runs.
        let renderer = Renderer::new(&ctx, &scene, requested)?;
        let mut renderer = built(&ctx, renderer, |r| r.set_frames_in_flight(&ctx, FRAMES_IN_FLIGHT))?;
        // An interactive view: auto primary visibility measures per view.
        renderer.choices.visibility.measure = true;
        let presenter =
            Presenter::new(&ctx, &window, opts.present_mode).inspect_err(|_| renderer.destroy(&ctx))?;
        let controller = CameraController::new(scene.bounds, scene.cameras.clone(), camera, start_index);
        let now = Instant::now();
        let mut v = Viewer {
            renderer,
            presenter,
            slots: Vec::new(),
            slot: 0,
            shots: Vec::new(),
            shot_request: None,
            shots_taken: 0,
            capture_request: false,
            scene,
            animation,
            scene_dirty: false,
            controller,
            // A frame sequence: glossy reflections converge over frames.
            settings: RenderSettings {
                glossy_temporal: true,
                exposure,
                tone,
                exposure_from_scene: false,
                ..job.settings
            },
            budget_keys: job.settings.budget.unwrap_or(BudgetSettings::effects(f64::INFINITY)),
            stats: FrameStats::new(now),
            needs_recreate: true,
            paused: false,
            last_recreate_try: now,
            last_frame: now,
            presented: 0,
            cursor: None,
            modifiers: ModifiersState::empty(),
            requested,
            frames: opts.frames,
            fixed_fps: opts.fixed_fps.filter(|f| *f > 0.0),
            screenshot: opts.screenshot.clone(),
            final_wait: None,
            resize_test: opts.test_resize.then(|| ResizeTest::new(requested)),
            scene_name,
            ctx,
            window,
        };
        // From here on Drop cleans up whatever exists.
        for i in 0..FRAMES_IN_FLIGHT {
            let slot = v.create_slot(i)?;
            v.slots.push(slot);
        }
        v.recreate()?;
        log::info!(
            "viewer: {} at {}x{}; keys: WASD/QE move, mouse drag look, O orbit, C/Ctrl+N cameras, R reset, \
             1-5/V/0 debug views, -/= exposure, M/X tone mapping, G anti-aliasing, F5-F7 effects, T hybrid/rt, P/F12 screenshot, F9 RenderDoc capture, Esc quit",
            v.scene_name,
            requested.width,
            requested.height
        );
        Ok(v)
    }

    fn create_slot(&self, i: usize) -> Result<FrameSlot> {
        let ctx = &self.ctx;
        let cmd = ctx.allocate_command_buffer(&format!("frame {i} commands"))?;
        let fence = unsafe {
            ctx.device
                .create_fence(&vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED), None)
        };
        let sem = unsafe { ctx.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) };
        match (fence, sem) {
            (Ok(fence), Ok(image_available)) => {
                ctx.name(fence, &format!("frame {i} in flight"));
                ctx.name(image_available, &format!("frame {i} image available"));
                Ok(FrameSlot { cmd, fence, image_available })
            }
            (f, s) => unsafe {
                if let Ok(f) = f {
                    ctx.device.destroy_fence(f, None);
                }
                if let Ok(s) = s {
                    ctx.device.destroy_semaphore(s, None);
                }
                ctx.device.free_command_buffers(ctx.command_pool, &[cmd]);
                bail!("creating frame {i}'s fence and semaphore failed");
            },
        }
    }

    fn window_extent(&self) -> vk::Extent2D {
        if self.resize_test.as_ref().is_some_and(|t| t.minimized()) {
            return vk::Extent2D { width: 0, height: 0 };
        }
        let s = self.window.inner_size();
        vk::Extent2D { width: s.width, height: s.height }
    }

    /// Recreates the swapchain for the window's size (or pauses at zero).
    pub(super) fn recreate(&mut self) -> Result<()> {
        unsafe { self.ctx.device.device_wait_idle() }.context("vkDeviceWaitIdle (device lost?)")?;
        self.finish_screenshots(None)?;
        self.last_recreate_try = Instant::now();
        let was_paused = self.paused;
        // A window with no area pauses whatever the surface still says (X11 keeps an iconified
        // window's extent).
        let window = self.window_extent();
        let ok = window.width > 0 && window.height > 0 && self.presenter.recreate(&self.ctx, window)?;
        self.needs_recreate = false;
        self.paused = !ok;
        if !ok {
            if !was_paused {
                log::info!("window has no area (minimized): rendering paused");
            }
            return Ok(());
        }
        if was_paused {
            log::info!("window restored: rendering resumed");
        }
        let extent = self.presenter.extent;
        if extent != self.renderer.extent() {
            self.renderer.resize(&self.ctx, extent)?;
        }
        Ok(())
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        let ctx = &self.ctx;
        unsafe {
            let _ = ctx.device.device_wait_idle();
        }
        for mut shot in self.shots.drain(..) {
            shot.buffer.destroy(ctx);
        }
        for s in self.slots.drain(..) {
            unsafe {
                ctx.device.destroy_fence(s.fence, None);
                ctx.device.destroy_semaphore(s.image_available, None);
                ctx.device.free_command_buffers(ctx.command_pool, &[s.cmd]);
            }
        }
        self.presenter.destroy(ctx);
        self.renderer.destroy(ctx);
    }
}
