//! Interactive viewer (`hybrid-rt view`): a winit window whose frames go through exactly the headless
//! frame path (`Renderer::prepare` + `Renderer::record`), then blit the final LDR image
//! (`Renderer::output_ldr`) into the swapchain image and present it.
//!
//! Frames in flight: two slots, each with its own command buffer, fence and image-available semaphore;
//! render-finished semaphores are per swapchain image (`swapchain.rs`). The renderer stages a frame's
//! host writes in its frame ring slot and reads results back through the same slot, so a frame waits
//! only for its own slot's fence (two frames ago) and is recorded while the previous one runs; the
//! results it reads (GPU times, bad pixels, budget statistics) are that older frame's.
//!
//! Keys: see README "Viewer".

pub mod camera_controller;
mod frame_loop;
mod input;
pub mod keys;
mod resize_test;
mod session;
pub mod stats;
pub mod swapchain;

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::WindowId;

use crate::app::{GpuOptions, RenderJob};
use crate::render::DebugView;
use session::Viewer;
pub use swapchain::PresentMode;

/// Command buffers / fences / image-available semaphores.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// The debug views in key order: 0 (lit), 1..6.
pub const DEBUG_VIEWS: [DebugView; 7] = [
    DebugView::None,
    DebugView::Albedo,
    DebugView::Normal,
    DebugView::Depth,
    DebugView::Material,
    DebugView::Object,
    DebugView::Selection,
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
    /// Advance the animation by 1 / fps per frame instead of wall-clock time: frame i shows time + i / fps,
    /// like `render` and `bench`.
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

/// Connects to the window system, or says why it cannot. Call once per process (winit allows one event loop).
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

/// Runs the viewer until the window closes (or `frames` are presented). Everything is destroyed before
/// returning; a validation error (leaks included, reported at device/instance destruction) fails it.
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
