//! Interactive viewer (`hybrid-rt view`): a winit window whose frames go
//! through exactly the headless frame path (`Renderer::prepare` +
//! `Renderer::record`), then blit the tone-mapped `targets.ldr` into the
//! swapchain image and present it.
//!
//! Frames in flight: two slots, each with its own command buffer, fence and
//! image-available semaphore; render-finished semaphores are per swapchain
//! image (see `swapchain.rs`). The renderer owns one set of targets and one
//! CPU-written frame-uniform buffer, so before `prepare` overwrites those
//! uniforms the viewer waits for the previous frame's fence. What still
//! overlaps: acquiring the next image (which may block on the presentation
//! engine) and window-event handling run while the GPU finishes the previous
//! frame. Full two-frame GPU overlap needs per-frame uniform buffers in the
//! renderer.
//!
//! Keys: see README "Viewer".

pub mod camera_controller;
pub mod stats;
pub mod swapchain;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;
use raw_window_handle::HasDisplayHandle;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, ModifiersState, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::app::{CameraChoice, GpuOptions, RenderJob};
use crate::render::frame::{Access, Use};
use crate::render::passes::tonemap::LDR;
use crate::render::shading::Mode;
use crate::render::{DebugView, FrameOutput, RenderSettings, Renderer};
use crate::scene::Scene;
use crate::vk::{image_barrier, memory_barrier, Buffer, Context, ContextOptions};
use camera_controller::{digit, CameraController};
use stats::FrameStats;
pub use swapchain::PresentMode;
use swapchain::{Acquired, Presenter};

/// Command buffers / fences / image-available semaphores.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// The debug views in key order: 0 (lit), 1..5.
pub const DEBUG_VIEWS: [DebugView; 6] = [
    DebugView::None,
    DebugView::Albedo,
    DebugView::Normal,
    DebugView::Depth,
    DebugView::Material,
    DebugView::Object,
];

/// What `hybrid-rt view` was asked to do.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    pub gpu: GpuOptions,
    /// Scene, window size, starting camera, exposure and debug view.
    pub job: RenderJob,
    pub present_mode: PresentMode,
    /// Exit after presenting this many frames.
    pub frames: Option<u64>,
    /// Advance the animation by 1 / fps per frame instead of by wall-clock
    /// time: frame i shows time + i / fps, like `render` and `bench`.
    pub fixed_fps: Option<f32>,
    /// With `frames`: PNG of the last frame. Without: where P / F12 write.
    pub screenshot: Option<PathBuf>,
    /// Automation for tests: resize the window twice, minimize and restore,
    /// then return to the requested size before the last frame.
    pub test_resize: bool,
}

/// No window can be opened here (no display, or the window system refused).
#[derive(Debug, thiserror::Error)]
#[error("cannot open a window: {0}")]
pub struct NoDisplay(pub String);

/// Connects to the window system, or says why it cannot. Call once per
/// process (winit allows one event loop).
pub fn open_display() -> Result<EventLoop<()>, NoDisplay> {
    let set = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
    if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
        return Err(NoDisplay("neither DISPLAY nor WAYLAND_DISPLAY is set".into()));
    }
    EventLoop::new().map_err(|e| {
        NoDisplay(format!(
            "{e} (DISPLAY={:?}, WAYLAND_DISPLAY={:?}; this build supports X11 only)",
            std::env::var("DISPLAY").unwrap_or_default(),
            std::env::var("WAYLAND_DISPLAY").unwrap_or_default()
        ))
    })
}

/// Runs the viewer until the window closes (or `frames` are presented).
/// Everything is destroyed before returning; the validation layer's error
/// count (leaks included, reported at device/instance destruction) makes it
/// fail.
pub fn run(event_loop: EventLoop<()>, opts: ViewerOptions) -> Result<()> {
    let mut app = App { opts, viewer: None, error: None };
    let loop_result = event_loop.run_app(&mut app);
    let viewer = app.viewer.take();
    let presented = viewer.as_ref().map(|v| v.presented);
    let counters = viewer.as_ref().map(|v| v.ctx.validation_counters());
    drop(viewer); // device idle, then swapchain, surface, renderer, context
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    loop_result.context("window event loop")?;
    if let Some(n) = presented {
        log::info!("presented {n} frames");
    }
    if let Some(errors) = counters.map(|c| c.errors()).filter(|e| *e > 0) {
        bail!("the Vulkan validation layer reported {errors} error(s); see the log above");
    }
    Ok(())
}

struct App {
    opts: ViewerOptions,
    viewer: Option<Viewer>,
    error: Option<anyhow::Error>,
}

enum Flow {
    Continue,
    Exit,
}

impl App {
    fn handle(&mut self, el: &ActiveEventLoop, r: Result<Flow>) {
        match r {
            Ok(Flow::Continue) => {}
            Ok(Flow::Exit) => el.exit(),
            Err(e) => {
                self.error.get_or_insert(e);
                el.exit();
            }
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.viewer.is_some() || self.error.is_some() {
            return;
        }
        match Viewer::new(el, &self.opts) {
            Ok(v) => self.viewer = Some(v),
            Err(e) => {
                self.error = Some(e);
                el.exit();
            }
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if el.exiting() || self.error.is_some() {
            return;
        }
        let Some(v) = self.viewer.as_mut() else { return };
        let r = v.window_event(event);
        self.handle(el, r);
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        if el.exiting() || self.error.is_some() {
            return;
        }
        let Some(v) = self.viewer.as_mut() else { return };
        let r = v.about_to_wait(el);
        self.handle(el, r);
    }
}

struct FrameSlot {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    image_available: vk::Semaphore,
}

/// A frame copied to a host buffer, written to PNG once its fence is done.
struct PendingShot {
    buffer: Buffer,
    extent: vk::Extent2D,
    path: PathBuf,
}

struct Viewer {
    renderer: Renderer,
    presenter: Presenter,
    slots: Vec<FrameSlot>,
    slot: usize,
    shot: Option<PendingShot>,
    shot_request: Option<PathBuf>,
    shots_taken: u32,
    scene: Scene,
    /// Animation being played: (index, clock in seconds, paused).
    animation: Option<(usize, f32, bool)>,
    /// The scene moved since the last frame: the renderer must update.
    scene_dirty: bool,
    controller: CameraController,
    settings: RenderSettings,
    stats: FrameStats,
    /// The renderer's timestamps hold a submitted frame not yet read.
    gpu_pending: bool,
    needs_recreate: bool,
    paused: bool,
    last_recreate_try: Instant,
    last_frame: Instant,
    presented: u64,
    cursor: Option<(f64, f64)>,
    modifiers: ModifiersState,
    requested: vk::Extent2D,
    frames: Option<u64>,
    fixed_fps: Option<f32>,
    screenshot: Option<PathBuf>,
    final_wait: Option<Instant>,
    resize_test: Option<ResizeTest>,
    scene_name: String,
    // Dropped after everything above is destroyed (see Drop): the context,
    // then the window the surface belonged to.
    ctx: Context,
    window: Window,
}

fn validate_extent(job: &RenderJob) -> Result<vk::Extent2D> {
    if job.width == 0 || job.height == 0 || job.width > 16384 || job.height > 16384 {
        bail!("resolution {}x{} out of range (1..=16384)", job.width, job.height);
    }
    Ok(vk::Extent2D { width: job.width, height: job.height })
}

impl Viewer {
    fn new(el: &ActiveEventLoop, opts: &ViewerOptions) -> Result<Viewer> {
        let job = &opts.job;
        let requested = validate_extent(job)?;
        let mut scene = Scene::load(&job.scene)?;
        let animation = match &job.animation {
            Some(a) => {
                let i = crate::scene::animation::find_animation(&scene, a)?;
                scene.animate(i, job.time);
                Some((i, job.time, false))
            }
            None => None,
        };
        let camera = job.camera.resolve(&scene)?;
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
            validation: g.validation,
            sync_validation: g.sync_validation,
            device: g.device.clone(),
            disable_ray_tracing: g.disable_ray_tracing,
            surface_extensions,
            swapchain: true,
        })?;
        let mut renderer = Renderer::new(&ctx, &scene, requested)?;
        let presenter = match Presenter::new(&ctx, &window, opts.present_mode) {
            Ok(p) => p,
            Err(e) => {
                renderer.destroy(&ctx);
                return Err(e);
            }
        };
        let controller = CameraController::new(scene.bounds, scene.cameras.clone(), camera, start_index);
        let now = Instant::now();
        let mut v = Viewer {
            renderer,
            presenter,
            slots: Vec::new(),
            slot: 0,
            shot: None,
            shot_request: None,
            shots_taken: 0,
            scene,
            animation,
            scene_dirty: false,
            controller,
            settings: job.settings,
            stats: FrameStats::new(now),
            gpu_pending: false,
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
             1-5/V/0 debug views, -/= exposure, F5-F7 effects, T hybrid/rt, P/F12 screenshot, Esc quit",
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
        let s = self.window.inner_size();
        vk::Extent2D { width: s.width, height: s.height }
    }

    /// Recreates the swapchain for the window's size (or pauses at zero).
    fn recreate(&mut self) -> Result<()> {
        unsafe { self.ctx.device.device_wait_idle() }.context("vkDeviceWaitIdle (device lost?)")?;
        self.finish_screenshot()?;
        self.last_recreate_try = Instant::now();
        let was_paused = self.paused;
        let ok = self.presenter.recreate(&self.ctx, self.window_extent())?;
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

    fn title(&self) -> String {
        let e = self.presenter.extent;
        let mut t = format!("hybrid-rt - {} - {}x{}", self.scene_name, e.width, e.height);
        if self.settings.debug_view != DebugView::None {
            t.push_str(&format!(" - {:?} view", self.settings.debug_view).to_lowercase());
        }
        if self.controller.mode() == camera_controller::Mode::Orbit {
            t.push_str(" - orbit");
        }
        if let Some(s) = &self.stats.last {
            t.push_str(&format!(" - {}", s.line()));
        }
        t
    }

    fn window_event(&mut self, event: WindowEvent) -> Result<Flow> {
        match event {
            WindowEvent::CloseRequested => return Ok(Flow::Exit),
            WindowEvent::Resized(_) => self.needs_recreate = true,
            WindowEvent::RedrawRequested => return self.frame(),
            WindowEvent::Focused(false) => self.controller.release_all(),
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else { return Ok(Flow::Continue) };
                if event.repeat {
                    return Ok(Flow::Continue);
                }
                let pressed = event.state == ElementState::Pressed;
                if self.controller.key(code, pressed, self.modifiers.control_key()) || !pressed {
                    return Ok(Flow::Continue);
                }
                return Ok(self.key(code));
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left | MouseButton::Right, .. } => {
                self.controller.mouse_button(state == ElementState::Pressed)
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.cursor {
                    self.controller.mouse_motion((position.x - x) as f32, (position.y - y) as f32);
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => match delta {
                MouseScrollDelta::LineDelta(_, y) => self.controller.scroll(y),
                MouseScrollDelta::PixelDelta(p) => self.controller.scroll(p.y as f32 / 40.0),
            },
            _ => {}
        }
        Ok(Flow::Continue)
    }

    /// Viewer keys (the camera's are handled by the controller).
    fn key(&mut self, code: KeyCode) -> Flow {
        match code {
            KeyCode::Escape => return Flow::Exit,
            KeyCode::F12 | KeyCode::KeyP => {
                let path = match &self.screenshot {
                    Some(p) if self.frames.is_none() => p.clone(),
                    _ => {
                        let secs = std::time::SystemTime::now()
                            .duration_since(std::time::UNIX_EPOCH)
                            .map(|d| d.as_secs())
                            .unwrap_or(0);
                        PathBuf::from(format!("out/screenshot-{secs}-{}.png", self.shots_taken))
                    }
                };
                self.shot_request = Some(path);
            }
            KeyCode::KeyV => {
                let i = DEBUG_VIEWS.iter().position(|v| *v == self.settings.debug_view).unwrap_or(0);
                self.set_debug_view(DEBUG_VIEWS[(i + 1) % DEBUG_VIEWS.len()]);
            }
            KeyCode::Minus | KeyCode::NumpadSubtract => {
                self.set_exposure(self.settings.exposure / 2f32.sqrt())
            }
            KeyCode::Equal | KeyCode::NumpadAdd => self.set_exposure(self.settings.exposure * 2f32.sqrt()),
            KeyCode::F5 => toggle("shadows", &mut self.settings.effects.shadows),
            KeyCode::F6 => toggle("reflections", &mut self.settings.effects.reflections),
            KeyCode::F7 => toggle("refractions", &mut self.settings.effects.refractions),
            KeyCode::F8 => log::info!("toggle the per-object heuristic: not available yet"),
            KeyCode::Space | KeyCode::Comma | KeyCode::Period => {
                if let Some((_, clock, paused)) = &mut self.animation {
                    match code {
                        KeyCode::Space => *paused = !*paused,
                        // Scrub a tenth of a second (pauses playback).
                        KeyCode::Comma => (*clock, *paused) = ((*clock - 0.1).max(0.0), true),
                        _ => (*clock, *paused) = (*clock + 0.1, true),
                    }
                    self.scene_dirty = true;
                    log::info!("animation t = {:.2} s{}", clock, if *paused { " (paused)" } else { "" });
                }
            }
            KeyCode::KeyT => {
                if self.ctx.rt.ray_query {
                    self.settings.mode = match self.settings.mode {
                        Mode::Hybrid => Mode::Rt,
                        Mode::Rt => Mode::Hybrid,
                    };
                    log::info!("render mode: {:?}", self.settings.mode);
                } else {
                    log::info!("render mode rt: not available (the device has no ray query)");
                }
            }
            _ => {
                if let Some(d) = digit(code).filter(|d| (*d as usize) < DEBUG_VIEWS.len()) {
                    let v = DEBUG_VIEWS[d as usize];
                    // The active view's key again goes back to the lit image.
                    self.set_debug_view(if v == self.settings.debug_view { DebugView::None } else { v });
                }
            }
        }
        Flow::Continue
    }

    fn set_debug_view(&mut self, v: DebugView) {
        self.settings.debug_view = v;
        log::info!("debug view: {v:?}");
        self.window.set_title(&self.title());
    }

    fn set_exposure(&mut self, e: f32) {
        self.settings.exposure = e.clamp(1.0 / 1024.0, 1024.0);
        log::info!("exposure: {:.3}", self.settings.exposure);
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) -> Result<Flow> {
        if let Some(t) = &mut self.resize_test {
            t.tick(&self.window, self.presented, self.presenter.extent, self.paused);
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

    /// Reads the GPU pass times of the last submitted frame (its fence is done).
    fn collect_gpu_times(&mut self) -> Result<()> {
        if std::mem::take(&mut self.gpu_pending) {
            let mut t = self.renderer.timer.results(&self.ctx)?;
            // The scene update (skinning, refit, TLAS) of the frame, when it had one.
            if self.animation.as_ref().is_some_and(|(_, _, paused)| !paused) {
                t.extend(self.renderer.update_timings.iter().copied());
            }
            self.stats.gpu(&t);
        }
        Ok(())
    }

    /// Writes a pending screenshot; its frame has completed.
    fn finish_screenshot(&mut self) -> Result<()> {
        let Some(mut shot) = self.shot.take() else { return Ok(()) };
        let r = (|| {
            let frame = FrameOutput {
                width: shot.extent.width,
                height: shot.extent.height,
                ldr: shot.buffer.read()?.to_vec(),
                hdr: Vec::new(),
                timings: Vec::new(),
                ray_counts: [0; 3],
            };
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

    fn frame(&mut self) -> Result<Flow> {
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
        let FrameSlot { cmd, fence, image_available } = self.slots[s];
        // This slot's previous frame (two ago) must be done with its command
        // buffer and image-available semaphore.
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
        // One set of targets and frame uniforms in the renderer: the previous
        // frame must finish before `prepare` rewrites them (and before its
        // timestamps are read).
        let prev = self.slots[(s + FRAMES_IN_FLIGHT - 1) % FRAMES_IN_FLIGHT].fence;
        unsafe { dev.wait_for_fences(&[prev], true, u64::MAX) }
            .context("waiting for a frame (device lost?)")?;
        self.renderer.finish_scene_update(&self.ctx)?;
        self.collect_gpu_times()?;
        self.finish_screenshot()?;

        self.controller.update(dt);
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
            self.shot = Some(PendingShot { buffer, extent: self.renderer.extent(), path });
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
        self.gpu_pending = true;
        self.needs_recreate |= self.presenter.present(self.ctx.queue, index)?;
        self.presented += 1;
        self.slot = (s + 1) % FRAMES_IN_FLIGHT;
        self.stats.frame_presented();

        let tick = self.stats.tick(Instant::now());
        if tick.title.is_some() {
            self.window.set_title(&self.title());
        }
        if let Some(line) = tick.log {
            log::info!("{line}");
        }
        if last {
            unsafe { self.ctx.device.device_wait_idle() }.context("vkDeviceWaitIdle")?;
            self.renderer.finish_scene_update(&self.ctx)?;
            self.collect_gpu_times()?;
            self.finish_screenshot()?;
            return Ok(Flow::Exit);
        }
        Ok(Flow::Continue)
    }

    /// The frame's commands: the scene update when `update`, the renderer's
    /// passes, then the blit of the tone-mapped image into swapchain image
    /// `index` (and a readback copy for a screenshot), ending in PRESENT_SRC.
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
        let uses = [Use::image(&LDR, Access::TransferRead)];
        self.renderer.record_with(ctx, cmd, |rec, t| {
            let ldr = t.get(&LDR).context("no tone-mapped output")?;
            rec.pass("present blit", vk::PipelineStageFlags2::NONE, &uses, |cmd| {
                let src = t.extent;
                // The swapchain image is outside the frame's targets: its
                // barriers are written here. Waits for the image-available
                // semaphore (its wait stage is BLIT).
                image_barrier(
                    ctx,
                    cmd,
                    image,
                    vk::ImageAspectFlags::COLOR,
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    (vk::PipelineStageFlags2::BLIT, vk::AccessFlags2::NONE),
                    (vk::PipelineStageFlags2::BLIT, vk::AccessFlags2::TRANSFER_WRITE),
                );
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
                if let Some(buf) = shot {
                    let copy = [vk::BufferImageCopy::default()
                        .image_subresource(layers)
                        .image_extent(vk::Extent3D { width: src.width, height: src.height, depth: 1 })];
                    unsafe {
                        ctx.device.cmd_copy_image_to_buffer(
                            cmd,
                            ldr.raw,
                            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                            buf.raw,
                            &copy,
                        )
                    };
                    memory_barrier(
                        ctx,
                        cmd,
                        (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
                        (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
                    );
                }
                image_barrier(
                    ctx,
                    cmd,
                    image,
                    vk::ImageAspectFlags::COLOR,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::ImageLayout::PRESENT_SRC_KHR,
                    (vk::PipelineStageFlags2::BLIT, vk::AccessFlags2::TRANSFER_WRITE),
                    (vk::PipelineStageFlags2::BOTTOM_OF_PIPE, vk::AccessFlags2::NONE),
                );
                Ok(())
            })
        })?;
        unsafe { ctx.device.end_command_buffer(cmd)? };
        Ok(())
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        let ctx = &self.ctx;
        unsafe {
            let _ = ctx.device.device_wait_idle();
        }
        if let Some(mut shot) = self.shot.take() {
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

/// Flips a secondary-effect switch (the shading pass is rebuilt on the next
/// `prepare`; effects the scene does not need stay off either way).
fn toggle(name: &str, on: &mut bool) {
    *on = !*on;
    log::info!("{name}: {}", if *on { "on" } else { "off" });
}

/// `--test-resize`: two resizes, a minimize/restore, then back to the
/// requested size, each step after a few presented frames.
struct ResizeTest {
    step: u32,
    since: Instant,
    since_frame: u64,
    original: vk::Extent2D,
    saw_pause: bool,
}

const TEST_SIZES: [(u32, u32); 2] = [(480, 270), (200, 120)];

impl ResizeTest {
    fn new(original: vk::Extent2D) -> Self {
        ResizeTest { step: 0, since: Instant::now(), since_frame: 0, original, saw_pause: false }
    }

    fn done(&self) -> bool {
        self.step >= 6
    }

    fn next(&mut self, presented: u64) {
        self.step += 1;
        self.since = Instant::now();
        self.since_frame = presented;
    }

    fn tick(&mut self, window: &Window, presented: u64, extent: vk::Extent2D, paused: bool) {
        let frames = presented.saturating_sub(self.since_frame);
        let waited = self.since.elapsed();
        let at = |(w, h): (u32, u32)| extent == vk::Extent2D { width: w, height: h };
        let request = |(w, h): (u32, u32)| {
            log::info!("test-resize: requesting {w}x{h}");
            let _ = window.request_inner_size(PhysicalSize::new(w, h));
        };
        match self.step {
            0 if presented >= 5 => {
                request(TEST_SIZES[0]);
                self.next(presented);
            }
            1 | 2 if frames >= 5 => {
                let size = TEST_SIZES[self.step as usize - 1];
                if !at(size) && waited < Duration::from_secs(5) {
                    return;
                }
                if !at(size) {
                    log::warn!("test-resize: the window did not become {}x{}", size.0, size.1);
                }
                if self.step == 1 {
                    request(TEST_SIZES[1]);
                } else {
                    log::info!("test-resize: minimizing");
                    window.set_minimized(true);
                }
                self.next(presented);
            }
            3 => {
                self.saw_pause |= paused;
                if waited >= Duration::from_millis(500) {
                    if self.saw_pause {
                        log::info!("test-resize: minimized, rendering paused; restoring");
                    } else {
                        log::info!(
                            "test-resize: the X server ignored the minimize request (no window manager?), \
                             is_minimized = {:?}; restoring",
                            window.is_minimized()
                        );
                    }
                    window.set_minimized(false);
                    self.next(presented);
                }
            }
            4 if !paused && waited >= Duration::from_millis(300) => {
                request((self.original.width, self.original.height));
                self.next(presented);
            }
            5 if at((self.original.width, self.original.height)) && frames >= 3 => {
                log::info!("test-resize: back at {}x{}, done", self.original.width, self.original.height);
                self.next(presented);
            }
            _ => {}
        }
    }
}
