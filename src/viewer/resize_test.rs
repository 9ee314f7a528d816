//! `--test-resize` automation: a scripted sequence of window resizes and a
//! minimize/restore, used by the end-to-end viewer test. The minimize is
//! asked of the window system and also driven through the viewer itself:
//! while it lasts the window reports no area, as a minimized window does
//! where the window system says so (Windows, Wayland), because an X server
//! without a window manager (Xvfb in CI) ignores the request and the pause
//! path would never run.

use std::time::{Duration, Instant};

use ash::vk;
use winit::dpi::PhysicalSize;
use winit::window::Window;

/// `--test-resize`: two resizes, a minimize/restore, then back to the
/// requested size, each step after a few presented frames.
pub(super) struct ResizeTest {
    step: u32,
    since: Instant,
    since_frame: u64,
    original: vk::Extent2D,
    saw_pause: bool,
    /// The window reports no area (`Viewer::window_extent`).
    minimized: bool,
}

const TEST_SIZES: [(u32, u32); 2] = [(480, 270), (200, 120)];

impl ResizeTest {
    pub(super) fn new(original: vk::Extent2D) -> Self {
        ResizeTest {
            step: 0,
            since: Instant::now(),
            since_frame: 0,
            original,
            saw_pause: false,
            minimized: false,
        }
    }

    /// The scripted minimize is on: the window has no area.
    pub(super) fn minimized(&self) -> bool {
        self.minimized
    }

    pub(super) fn done(&self) -> bool {
        self.step >= 6
    }

    fn next(&mut self, presented: u64) {
        self.step += 1;
        self.since = Instant::now();
        self.since_frame = presented;
    }

    /// One step of the script; true when the window's area changed without a resize event (the
    /// scripted minimize or restore): the caller looks at the surface again.
    pub(super) fn tick(
        &mut self,
        window: &Window,
        presented: u64,
        extent: vk::Extent2D,
        paused: bool,
    ) -> bool {
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
                    return false;
                }
                if !at(size) {
                    log::warn!("test-resize: the window did not become {}x{}", size.0, size.1);
                }
                if self.step == 1 {
                    request(TEST_SIZES[1]);
                } else {
                    log::info!("test-resize: minimizing");
                    window.set_minimized(true);
                    self.minimized = true;
                }
                self.next(presented);
                return self.minimized;
            }
            3 => {
                self.saw_pause |= paused;
                if waited >= Duration::from_millis(500) {
                    if self.saw_pause {
                        log::info!("test-resize: minimized, rendering paused; restoring");
                    } else {
                        log::warn!("test-resize: minimized for 500 ms and rendering never paused; restoring");
                    }
                    window.set_minimized(false);
                    self.minimized = false;
                    self.next(presented);
                    return true;
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
        false
    }
}
