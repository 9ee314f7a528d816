//! Frame statistics: frames per second and per-pass GPU milliseconds (from the renderer's timestamp
//! queries), averaged over short windows: 0.5 s for the window title, 2 s for the log.

use std::time::{Duration, Instant};

/// Averages over one time window.
#[derive(Clone, Debug)]
pub struct Window {
    length: Duration,
    start: Instant,
    frames: u32,
    /// Pass name, summed ms, samples.
    gpu: Vec<(&'static str, f64, u32)>,
    /// NaN/Inf pixels tone mapping met, summed over the window's frames.
    bad_pixels: u64,
}

/// One window's averages.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    pub fps: f64,
    /// Mean CPU frame time, ms.
    pub frame_ms: f64,
    /// Mean GPU ms per pass, in recording order.
    pub passes: Vec<(&'static str, f64)>,
    /// NaN/Inf pixels over the window (shown magenta; never silent).
    pub bad_pixels: u64,
}

impl Summary {
    /// GPU ms of all passes together.
    pub fn gpu_total(&self) -> f64 {
        self.passes.iter().map(|(_, ms)| ms).sum()
    }

    /// "12.3 fps (81.3 ms) | GPU 7.20 ms: gbuffer 1.00, direct 5.00, ..."
    pub fn line(&self) -> String {
        let mut s = format!("{:.1} fps ({:.1} ms)", self.fps, self.frame_ms);
        if !self.passes.is_empty() {
            let parts: Vec<_> = self.passes.iter().map(|(n, ms)| format!("{n} {ms:.2}")).collect();
            s.push_str(&format!(" | GPU {:.2} ms: {}", self.gpu_total(), parts.join(", ")));
        }
        if self.bad_pixels > 0 {
            s.push_str(&format!(" | {} NaN/Inf pixels", self.bad_pixels));
        }
        s
    }
}

impl Window {
    pub fn new(length: Duration, now: Instant) -> Window {
        Window { length, start: now, frames: 0, gpu: Vec::new(), bad_pixels: 0 }
    }

    pub fn frame(&mut self) {
        self.frames += 1;
    }

    /// Adds one frame's pass timings (NaN = no timestamps: skipped).
    pub fn gpu(&mut self, timings: &[(&'static str, f64)]) {
        for &(name, ms) in timings.iter().filter(|(_, ms)| ms.is_finite()) {
            match self.gpu.iter_mut().find(|(n, _, _)| *n == name) {
                Some(e) => {
                    e.1 += ms;
                    e.2 += 1;
                }
                None => self.gpu.push((name, ms, 1)),
            }
        }
    }

    /// The averages once the window is over (and starts the next one).
    pub fn tick(&mut self, now: Instant) -> Option<Summary> {
        let elapsed = now.saturating_duration_since(self.start);
        if elapsed < self.length {
            return None;
        }
        let secs = elapsed.as_secs_f64().max(1e-9);
        let s = Summary {
            fps: self.frames as f64 / secs,
            frame_ms: if self.frames > 0 { secs * 1e3 / self.frames as f64 } else { f64::NAN },
            passes: self.gpu.iter().map(|(n, sum, k)| (*n, sum / (*k).max(1) as f64)).collect(),
            bad_pixels: self.bad_pixels,
        };
        *self = Window::new(self.length, now);
        Some(s)
    }
}

/// The viewer's two windows: title (0.5 s) and log (2 s).
pub struct FrameStats {
    title: Window,
    log: Window,
    pub last: Option<Summary>,
}

/// What changed on a tick.
#[derive(Default)]
pub struct Tick {
    /// New text for the window title's statistics part.
    pub title: Option<String>,
    /// A line to log.
    pub log: Option<String>,
}

impl FrameStats {
    pub fn new(now: Instant) -> FrameStats {
        FrameStats {
            title: Window::new(Duration::from_millis(500), now),
            log: Window::new(Duration::from_secs(2), now),
            last: None,
        }
    }

    pub fn frame_presented(&mut self) {
        self.title.frame();
        self.log.frame();
    }

    pub fn gpu(&mut self, timings: &[(&'static str, f64)]) {
        self.title.gpu(timings);
        self.log.gpu(timings);
    }

    /// NaN/Inf pixels of one frame.
    pub fn bad_pixels(&mut self, n: u32) {
        self.title.bad_pixels += n as u64;
        self.log.bad_pixels += n as u64;
    }

    pub fn tick(&mut self, now: Instant) -> Tick {
        let mut t = Tick::default();
        if let Some(s) = self.title.tick(now) {
            t.title = Some(s.line());
            self.last = Some(s);
        }
        if let Some(s) = self.log.tick(now) {
            t.log = Some(s.line());
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn averages_fps_and_pass_times_over_the_window() {
        let t0 = Instant::now();
        let mut w = Window::new(Duration::from_secs(2), t0);
        for i in 0..10 {
            w.frame();
            w.gpu(&[("gbuffer", 1.0), ("lighting", 2.0 + (i % 2) as f64), ("x", f64::NAN)]);
        }
        assert!(w.tick(t0 + Duration::from_secs(1)).is_none());
        let s = w.tick(t0 + Duration::from_secs(2)).unwrap();
        assert!((s.fps - 5.0).abs() < 1e-9);
        assert!((s.frame_ms - 200.0).abs() < 1e-9);
        assert_eq!(s.passes, vec![("gbuffer", 1.0), ("lighting", 2.5)]);
        assert!((s.gpu_total() - 3.5).abs() < 1e-12);
        assert!(
            s.line().starts_with("5.0 fps (200.0 ms) | GPU 3.50 ms: gbuffer 1.00, lighting 2.50"),
            "{}",
            s.line()
        );
        // The next window starts empty.
        let s = w.tick(t0 + Duration::from_secs(4)).unwrap();
        assert_eq!(s.fps, 0.0);
        assert!(s.passes.is_empty());
        assert_eq!(s.line(), "0.0 fps (NaN ms)");
    }

    #[test]
    fn title_ticks_more_often_than_the_log() {
        let t0 = Instant::now();
        let mut st = FrameStats::new(t0);
        st.frame_presented();
        let t = st.tick(t0 + Duration::from_millis(600));
        assert!(t.title.is_some() && t.log.is_none());
        let t = st.tick(t0 + Duration::from_millis(2100));
        assert!(t.title.is_some() && t.log.is_some());
    }
}
