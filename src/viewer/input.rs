//! Window events and keys: camera input goes to the controller; viewer keys change the render settings
//! (debug view, exposure, tone mapping, effects, the ray-tracing budget, mode, AA), the animation clock
//! or request a screenshot; the window title shows them.

use std::path::PathBuf;

use anyhow::Result;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{KeyCode, PhysicalKey};

use super::camera_controller::{self, digit};
use super::session::Viewer;
use super::{Flow, DEBUG_VIEWS};
use crate::render::budget::{BudgetMode, BudgetReport, BudgetSettings, Fallback};
use crate::render::shading::{AaMode, Mode};
use crate::render::tone::{AutoExposure, ToneOperator, ToneSettings};
use crate::render::DebugView;

impl Viewer {
    pub(super) fn title(&self) -> String {
        let e = self.presenter.extent;
        let mut t = format!("hybrid-rt - {} - {}x{}", self.scene_name, e.width, e.height);
        if self.settings.debug_view != DebugView::None {
            t.push_str(&format!(" - {:?} view", self.settings.debug_view).to_lowercase());
        }
        if self.settings.mode == Mode::Path {
            let spp = self.renderer.reference_frames() * crate::gpu::shared::PATH_SAMPLES_PER_FRAME;
            t.push_str(&format!(" - path traced, {spp} samples per pixel"));
        }
        if self.settings.tone != ToneSettings::default() {
            t.push_str(&format!(" - {}", self.settings.tone.describe()));
        }
        if self.settings.aa != AaMode::Edge {
            t.push_str(&format!(" - aa {}", self.settings.aa.name()));
        }
        if self.controller.mode() == camera_controller::Mode::Orbit {
            t.push_str(" - orbit");
        }
        if let Some(b) = &self.settings.budget {
            t.push_str(&format!(" - {}", self.budget_title(b)));
        }
        if let Some(s) = &self.stats.last {
            t.push_str(&format!(" - {}", s.line()));
        }
        t
    }

    pub(super) fn window_event(&mut self, event: WindowEvent) -> Result<Flow> {
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
            KeyCode::F9 => {
                if self.ctx.renderdoc.is_some() {
                    log::info!("renderdoc: capturing the next frame");
                    self.capture_request = true;
                } else {
                    log::warn!(
                        "F9: RenderDoc is not loaded: start the viewer under `renderdoccmd capture ...` \
                         or with --capture-frame N"
                    );
                }
            }
            KeyCode::KeyV => {
                let i = DEBUG_VIEWS.iter().position(|v| *v == self.settings.debug_view).unwrap_or(0);
                self.set_debug_view(DEBUG_VIEWS[(i + 1) % DEBUG_VIEWS.len()]);
            }
            KeyCode::Minus | KeyCode::NumpadSubtract => {
                self.set_exposure(self.settings.exposure / 2f32.sqrt())
            }
            KeyCode::Equal | KeyCode::NumpadAdd => self.set_exposure(self.settings.exposure * 2f32.sqrt()),
            KeyCode::KeyM => {
                let ops = ToneOperator::ALL;
                let i = ops.iter().position(|o| *o == self.settings.tone.operator).unwrap_or(0);
                self.settings.tone.operator = ops[(i + 1) % ops.len()];
                log::info!("tone mapping: {}", self.settings.tone.describe());
                self.window.set_title(&self.title());
            }
            KeyCode::KeyX => {
                self.settings.tone.auto_exposure = match self.settings.tone.auto_exposure {
                    AutoExposure::Off => AutoExposure::LogAverage,
                    AutoExposure::LogAverage => AutoExposure::Histogram,
                    AutoExposure::Histogram => AutoExposure::Off,
                };
                log::info!("tone mapping: {}", self.settings.tone.describe());
                self.window.set_title(&self.title());
            }
            KeyCode::F5 => toggle("shadows", &mut self.settings.effects.shadows),
            KeyCode::F6 => toggle("reflections", &mut self.settings.effects.reflections),
            KeyCode::F7 => toggle("refractions", &mut self.settings.effects.refractions),
            KeyCode::F8 => {
                // Off -> effects mode -> paper mode -> off, each starting at every visible object; [ and ]
                // then halve / double it. Stickiness and fallback carry over (the command line's at first).
                if let Some(b) = self.settings.budget {
                    self.budget_keys = b;
                }
                let keep = |mode| Some(BudgetSettings { mode, budget: f64::INFINITY, ..self.budget_keys });
                self.settings.budget = match self.settings.budget.map(|b| b.mode) {
                    None => keep(BudgetMode::Effects),
                    Some(BudgetMode::Effects) => keep(BudgetMode::Paper),
                    Some(BudgetMode::Paper) => None,
                };
                self.log_budget();
            }
            KeyCode::KeyB => match &mut self.settings.budget {
                Some(b) => {
                    b.fallback = match b.fallback {
                        Fallback::Raster => Fallback::None,
                        Fallback::None => Fallback::Raster,
                    };
                    self.log_budget();
                }
                None => log::info!("B: F8 turns the ray-tracing budget on first"),
            },
            KeyCode::BracketLeft | KeyCode::BracketRight => {
                let up = code == KeyCode::BracketRight;
                let report = self.renderer.budget_report();
                match &mut self.settings.budget {
                    Some(b) => match step_budget(b.budget, cost_of_everything(report, b), up) {
                        Some(t) => b.budget = t,
                        None => log::info!(
                            "[ / ]: no frame has measured what tracing everything costs yet; press again"
                        ),
                    },
                    None => log::info!("[ / ]: F8 turns the ray-tracing budget on first"),
                }
                self.log_budget();
            }
            KeyCode::Semicolon => {
                if let Some(b) = &mut self.settings.budget {
                    const STEPS: [f32; 4] = [0.0, 10.0, 100.0, 1000.0];
                    let i =
                        STEPS.iter().position(|s| *s == b.stickiness).map_or(0, |i| (i + 1) % STEPS.len());
                    b.stickiness = STEPS[i];
                }
                self.log_budget();
            }
            KeyCode::KeyG => {
                let all = AaMode::ALL;
                let i = all.iter().position(|m| *m == self.settings.aa).unwrap_or(0);
                self.settings.aa = all[(i + 1) % all.len()];
                log::info!("anti-aliasing: {}", self.settings.aa.name());
                self.window.set_title(&self.title());
            }
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
            KeyCode::KeyK => {
                // The ground truth, accumulating while nothing moves.
                self.settings.mode = if self.settings.mode == Mode::Path { Mode::Hybrid } else { Mode::Path };
                if self.settings.mode == Mode::Path {
                    self.settings.debug_view = DebugView::None;
                }
                log::info!("render mode: {:?}", self.settings.mode);
                self.window.set_title(&self.title());
            }
            KeyCode::KeyT => {
                if self.ctx.rt.ray_query {
                    self.settings.mode = match self.settings.mode {
                        Mode::Hybrid => Mode::Rt,
                        Mode::Rt | Mode::Path => Mode::Hybrid,
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

    /// "budget 1.2e4 (3/6 objects, rays 4.1 ms)" (paper mode) or "budget
    /// 4.00 ms (3/6 objects, rays 4.1 ms)" (effects mode): T, what the last
    /// selection took, and the ray passes' GPU time in the last stats window.
    fn budget_title(&self, b: &BudgetSettings) -> String {
        let mut t = format!("budget {}", budget_text(b));
        if b.stickiness > 0.0 {
            t.push_str(&format!(" I {}", b.stickiness));
        }
        if let Some(r) = self.renderer.budget_report() {
            let visible = r.objects.iter().filter(|o| o.pixels > 0).count();
            t.push_str(&format!(" ({}/{visible} objects", r.selection.selected.len()));
            if let Some(s) = &self.stats.last {
                let ray_ms: f64 = s
                    .passes
                    .iter()
                    .filter(|(n, _)| crate::render::budget::effects::STAGES.iter().any(|s| s.contains(n)))
                    .map(|(_, ms)| ms)
                    .sum();
                t.push_str(&format!(", rays {ray_ms:.2} ms"));
            }
            t.push(')');
        }
        t
    }

    fn log_budget(&mut self) {
        match &self.settings.budget {
            Some(b) => {
                log::info!(
                    "ray-tracing budget {} ({:?} mode, stickiness {}, fallback {:?})",
                    budget_text(b),
                    b.mode,
                    b.stickiness,
                    b.fallback
                )
            }
            None => log::info!("ray-tracing budget off: every object traced"),
        }
        self.window.set_title(&self.title());
    }

    fn set_debug_view(&mut self, v: DebugView) {
        if self.settings.mode == Mode::Path && v != DebugView::None {
            log::info!("debug views show the G-buffer, which path mode has not (K: back to hybrid)");
            return;
        }
        self.settings.debug_view = v;
        log::info!("debug view: {v:?}");
        self.window.set_title(&self.title());
    }

    fn set_exposure(&mut self, e: f32) {
        self.settings.exposure = e.clamp(1.0 / 1024.0, 1024.0);
        log::info!("exposure: {:.3}", self.settings.exposure);
    }
}

/// Flips a secondary-effect switch (the frame's passes are rebuilt on the next
/// `prepare`; effects the scene does not need stay off either way).
fn toggle(name: &str, on: &mut bool) {
    *on = !*on;
    log::info!("{name}: {}", if *on { "on" } else { "off" });
}

/// T as people read it: "everything" (not yet limited), "12.3k" paper-mode
/// units or "4.00 ms" in effects mode.
fn budget_text(b: &BudgetSettings) -> String {
    match (b.mode, b.budget) {
        (_, t) if !t.is_finite() => "everything".into(),
        (BudgetMode::Effects, t) => format!("{t:.2} ms"),
        (BudgetMode::Paper, t) if t >= 1e4 => format!("{:.1}k", t / 1e3),
        (BudgetMode::Paper, t) => format!("{t:.1}"),
    }
}

/// What tracing everything cost in `b`'s unit (effects mode: the ray stages' measured ms; paper mode:
/// the estimated cost units), from the last selection's `report` when it was made in `b`'s mode from
/// everything. None before such a frame: right after F8 the last report is the previous mode's (paper
/// units read as ms, or ms as paper units, which made `[` a budget of nearly 0) or a limited budget's.
fn cost_of_everything(report: Option<&BudgetReport>, b: &BudgetSettings) -> Option<f64> {
    let r = report.filter(|r| r.settings.mode == b.mode && r.settings.budget.is_infinite())?;
    let t = match r.settings.mode {
        BudgetMode::Effects => r.measured_ms,
        BudgetMode::Paper => r.selection.spent,
    };
    (t.is_finite() && t > 0.0).then_some(t)
}

/// [ (halve) or ] (double) on budget `t`; from "everything" (infinite) the step starts at what tracing
/// everything cost (`everything`, [`cost_of_everything`]), and is not taken (None) without it.
fn step_budget(t: f64, everything: Option<f64>, up: bool) -> Option<f64> {
    let base = if t.is_finite() { t } else { everything.filter(|e| *e > 0.0)? };
    Some(if up { base * 2.0 } else { base * 0.5 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::budget::Selection;

    #[test]
    fn budget_steps_wait_for_a_measurement() {
        // F8 then [ before any frame measured "everything": no step to 0.
        assert_eq!(step_budget(f64::INFINITY, None, false), None);
        assert_eq!(step_budget(f64::INFINITY, Some(0.0), false), None);
        assert_eq!(step_budget(f64::INFINITY, Some(8.0), false), Some(4.0));
        assert_eq!(step_budget(3.0, None, true), Some(6.0));
    }

    /// The last selection's report, made under `settings`, with `measured_ms` and `spent`.
    fn report(settings: BudgetSettings, measured_ms: f64, spent: f64) -> BudgetReport {
        BudgetReport {
            settings,
            objects: Vec::new(),
            selection: Selection { selected: Vec::new(), spent, mask: Vec::new() },
            effects: Vec::new(),
            predicted_ms: (settings.mode == BudgetMode::Effects).then_some(spent),
            measured_ms,
            predicted_rays: None,
            measured_rays: [0.0; 2],
            shadow_maps: false,
            traced: Vec::new(),
            traced_maps: false,
        }
    }

    #[test]
    fn budget_steps_start_from_everything_in_the_same_mode() {
        let inf = f64::INFINITY;
        let (effects, paper) = (BudgetSettings::effects(inf), BudgetSettings::paper(inf));
        // An effects-mode frame that traced everything in 29 ms (predicted 27), estimated at 1.2e5 units.
        let effects_frame = report(effects, 29.0, 27.0);
        let paper_frame = report(paper, f64::NAN, 1.2e5);
        assert_eq!(cost_of_everything(Some(&effects_frame), &effects), Some(29.0));
        assert_eq!(cost_of_everything(Some(&paper_frame), &paper), Some(1.2e5));
        // F8 from effects to paper mode, then [ before a paper-mode frame: the 29 ms are not 29 paper
        // units (half of that selects nothing: a budget of 0 in all but name).
        assert_eq!(cost_of_everything(Some(&effects_frame), &paper), None, "ms taken for paper units");
        assert_eq!(step_budget(inf, cost_of_everything(Some(&effects_frame), &paper), false), None);
        // Nor are paper units ms.
        assert_eq!(cost_of_everything(Some(&paper_frame), &effects), None, "paper units taken for ms");
        // A limited budget's frame measured less than everything.
        assert_eq!(cost_of_everything(Some(&report(BudgetSettings::effects(4.0), 3.9, 3.5)), &effects), None);
        // The first frames measure nothing (NaN, or 0 before the GPU times arrive).
        assert_eq!(cost_of_everything(Some(&report(effects, f64::NAN, 27.0)), &effects), None);
        assert_eq!(cost_of_everything(Some(&report(effects, 0.0, 27.0)), &effects), None);
        assert_eq!(cost_of_everything(None, &effects), None);
        // Stickiness and fallback do not change what everything costs.
        let sticky = BudgetSettings { stickiness: 10.0, fallback: Fallback::None, ..effects };
        assert_eq!(cost_of_everything(Some(&effects_frame), &sticky), Some(29.0));
        assert_eq!(step_budget(inf, Some(29.0), false), Some(14.5));
    }

    #[test]
    fn budget_values_read_short() {
        let b = |mode, budget| BudgetSettings { mode, budget, ..BudgetSettings::paper(0.0) };
        assert_eq!(budget_text(&b(BudgetMode::Effects, 29.0042135)), "29.00 ms");
        assert_eq!(budget_text(&b(BudgetMode::Paper, 29.0042135)), "29.0");
        assert_eq!(budget_text(&b(BudgetMode::Paper, 123456.7)), "123.5k");
        assert_eq!(budget_text(&b(BudgetMode::Paper, f64::INFINITY)), "everything");
    }
}
