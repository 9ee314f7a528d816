//! `--primary-visibility auto`: the hybrid frame's primary hits come from
//! the raster visibility buffer (pass `gbuffer`) or from camera rays (pass
//! `visibility_trace`), whichever the GPU timestamps say is cheaper for the
//! current view. On lavapipe neither always wins: Sponza's many instances
//! rasterize about as fast as they trace, the armadillo's 345k small
//! triangles rasterize ~3x slower than they trace
//! (bench/results/lavapipe-2core-vm-raster.md). Both passes write the same
//! hit ids, so everything after them is the same either way.
//!
//! How: with nothing measured for the view, probe frames record both
//! passes (the traced one last: its hit ids are the frame's) and their GPU
//! timestamps give both costs; each pass's cost is its least over
//! `PROBE_SAMPLES` probe frames. A pass's first frame after it was created
//! is not counted (a software device compiles its shaders there), so the
//! first probe of a new pass set takes one frame more. Then the cheaper is
//! kept and the decision logged with both times; later frames record only
//! it. The view is measured again when the camera has turned
//! or moved a lot since the last probe, and every `REPROBE_FRAMES` frames.

use glam::Vec3;

use super::settings::{PrimaryVisibility, RenderSettings};
use super::shading::{Mode, ShadingConfig};
use crate::scene::{Aabb, Camera};

/// The two techniques, by the name of the pass that implements each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Technique {
    Raster,
    Traced,
}

impl Technique {
    pub fn pass(self) -> &'static str {
        match self {
            Technique::Raster => super::passes::gbuffer::PASS.name,
            Technique::Traced => super::passes::visibility_trace::PASS.name,
        }
    }
    fn name(self) -> &'static str {
        match self {
            Technique::Raster => "raster",
            Technique::Traced => "traced",
        }
    }
}

/// Frames after which a still view is measured again.
pub const REPROBE_FRAMES: u32 = 300;
/// A probe costs both passes: at most one in this many frames, however
/// fast the camera moves.
pub const MIN_PROBE_INTERVAL: u32 = 30;
/// Probe frames per decision. One probe frame is one noisy sample (on a
/// shared 2-core lavapipe machine Sponza's raster probe read 27-73 ms
/// across runs against ~30 ms in steady frames); other work on the cores
/// only ever adds time, so the least of a few samples is the steadier
/// estimate of a pass's cost.
pub const PROBE_SAMPLES: u32 = 3;
/// The technique in use (raster before any decision) is kept unless the
/// other costs less than this fraction of it, so near-equal costs do not
/// flip the choice.
pub const SWITCH_BELOW: f64 = 0.8;
/// The camera turned more than this (radians, ~20 degrees) since the
/// measurement: measure again.
const REPROBE_TURN: f32 = 0.35;
/// The camera moved more than this fraction of the scene's bounding-box
/// diagonal since the measurement: measure again.
const REPROBE_MOVE: f32 = 0.1;

/// `settings` as a renderer that does (`measure`) or does not measure
/// sees them: without measuring, auto is raster, so `render`, tests and
/// golden images never depend on timing.
pub fn effective(settings: &RenderSettings, measure: bool) -> RenderSettings {
    match settings.primary_visibility {
        PrimaryVisibility::Auto if !measure => {
            RenderSettings { primary_visibility: PrimaryVisibility::Raster, ..*settings }
        }
        _ => *settings,
    }
}

/// What a frame records under auto.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recording {
    /// A probe: both passes, both timed.
    Both,
    One(Technique),
}

/// The per-view choice under auto (unused otherwise).
#[derive(Debug, Default)]
pub struct Chooser {
    /// Auto measures and chooses only when set (the viewer, `bench`);
    /// otherwise auto is raster (`effective`).
    pub measure: bool,
    /// Whether the frame's configuration chooses at all (hybrid, auto).
    active: bool,
    /// Both passes have run once since they were created (shaders compiled).
    warm: bool,
    /// What the prepared frame records (None: not choosing).
    recording: Option<Recording>,
    /// The technique kept and the probe's times (raster, traced) it was
    /// chosen by (None: the view is being probed).
    chosen: Option<(Technique, f64, f64)>,
    /// The last decision, kept across probes (for `bench`).
    last: Option<(Technique, f64, f64)>,
    /// Frames since the last decision.
    frames: u32,
    /// The probe under way: warm samples taken and each technique's least
    /// time (raster, traced) so far (None: none yet).
    samples: Option<(u32, f64, f64)>,
    /// Camera position and forward direction of the last probe.
    view: Option<(Vec3, Vec3)>,
}

impl Chooser {
    /// The passes were (re)made for `config`: both are cold again.
    pub fn passes_rebuilt(&mut self, config: &ShadingConfig) {
        self.active = config.mode == Mode::Hybrid && config.visibility == PrimaryVisibility::Auto;
        self.warm = false;
        self.samples = None;
    }

    /// Before a frame of `config` seen by `camera` in a scene within
    /// `bounds`: whether it rasterizes (needs the G-buffer draw list).
    pub fn before_frame(&mut self, camera: &Camera, bounds: &Aabb, config: Option<ShadingConfig>) -> bool {
        let size = (bounds.max - bounds.min).length();
        let choice = self.choose(camera.position(), camera.forward(), size);
        config.is_some_and(|c| c.mode == Mode::Hybrid && !c.visibility.is_traced())
            && choice != Some(Recording::One(Technique::Traced))
    }

    /// What the next frame records (None: not choosing).
    pub fn choose(&mut self, position: Vec3, forward: Vec3, scene_size: f32) -> Option<Recording> {
        if !self.active {
            self.recording = None;
            return None;
        }
        let changed = self.view.is_none_or(|(p, f)| {
            p.distance(position) > REPROBE_MOVE * scene_size || f.angle_between(forward) > REPROBE_TURN
        });
        // A probe under way finishes even if the camera keeps moving.
        let due = changed && self.frames >= MIN_PROBE_INTERVAL || self.frames >= REPROBE_FRAMES;
        if self.chosen.is_some() && due {
            log::debug!("primary visibility: measuring again (view changed, or {REPROBE_FRAMES} frames)");
            self.chosen = None;
            self.samples = None;
        }
        if self.chosen.is_none() {
            self.view = Some((position, forward));
        }
        let r = match self.chosen {
            Some((t, ..)) => Recording::One(t),
            None => Recording::Both,
        };
        self.recording = Some(r);
        Some(r)
    }

    /// Whether the prepared frame leaves out pass `name`: the technique it
    /// does not record, and with traced visibility alone the resolve of the
    /// raster's hits (the traced pass resolves its own). A probe records
    /// the resolve after both, since it is part of the raster's cost.
    pub fn leaves_out(&self, name: &str) -> bool {
        match self.recording {
            Some(Recording::One(Technique::Raster)) => name == Technique::Traced.pass(),
            Some(Recording::One(Technique::Traced)) => {
                name == Technique::Raster.pass() || name == super::passes::gbuffer_resolve::PASS.name
            }
            _ => false,
        }
    }

    /// After the frame completed, with its GPU pass times.
    pub fn after_frame(&mut self, timings: &[(&'static str, f64)]) {
        let Some(r) = self.recording else { return };
        self.frames += 1;
        if r != Recording::Both {
            return;
        }
        let ms = |name: &str| timings.iter().find(|(n, _)| *n == name).map(|(_, ms)| *ms);
        let (Some(raster), Some(traced)) = (ms(Technique::Raster.pass()), ms(Technique::Traced.pass()))
        else {
            return;
        };
        // The raster's hits need the resolve pass; the traced pass resolves
        // its own.
        let raster = raster + ms(super::passes::gbuffer_resolve::PASS.name).unwrap_or(0.0);
        if !std::mem::replace(&mut self.warm, true) {
            return; // compile time, not the passes' cost
        }
        let (n, raster, traced) = match self.samples {
            Some((n, r, t)) => (n + 1, r.min(raster), t.min(traced)),
            None => (1, raster, traced),
        };
        self.samples = Some((n, raster, traced));
        if n < PROBE_SAMPLES {
            return;
        }
        self.samples = None;
        let (current, other, current_ms, other_ms) = match self.last {
            Some((Technique::Traced, ..)) => (Technique::Traced, Technique::Raster, traced, raster),
            _ => (Technique::Raster, Technique::Traced, raster, traced),
        };
        let pick = if other_ms < SWITCH_BELOW * current_ms { other } else { current };
        if self.last.is_none_or(|(t, ..)| t != pick) {
            log::info!(
                "primary visibility: {} (for this view: raster {raster:.2} ms, traced {traced:.2} ms; a switch \
                 needs the other below {SWITCH_BELOW}x)",
                pick.name()
            );
        }
        self.chosen = Some((pick, raster, traced));
        self.last = self.chosen;
        self.frames = 0;
    }

    /// For `bench`: what the last frame recorded and the last probe's
    /// times. None when not choosing.
    pub fn describe(&self) -> Option<String> {
        let what = match self.recording? {
            Recording::Both => "both (a probe)",
            Recording::One(t) => t.name(),
        };
        Some(match self.last {
            Some((t, r, tr)) => format!(
                "primary visibility: auto, last frame {what}; chose {} by the last probe: raster {r:.2} ms, \
                 traced {tr:.2} ms",
                t.name()
            ),
            None => format!("primary visibility: auto, last frame {what} (no probe measured yet)"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hybrid_auto() -> ShadingConfig {
        let needs = super::super::shading::SceneNeeds {
            shadows: false,
            reflections: false,
            refractions: false,
            shadow_maps: false,
            largest_primitive_triangles: 1,
            instances: 1,
        };
        ShadingConfig {
            mode: Mode::Hybrid,
            effects: super::super::shading::Effects::NONE,
            backend: None,
            debug_view: false,
            needs,
            luminance: false,
            budget: false,
            shadow_fallback: false,
            aa: super::super::shading::AaMode::None,
            reference: false,
            visibility: PrimaryVisibility::Auto,
            occlusion: false,
        }
    }

    /// One frame at `pos`; the raster costs `raster` ms (gbuffer and its
    /// 1-ms resolve), the traced pass `traced` ms.
    fn frame(c: &mut Chooser, pos: Vec3, raster: f64, traced: f64) -> Recording {
        let r = c.choose(pos, Vec3::NEG_Z, 10.0).unwrap();
        // The resolve pass takes 1 ms (part of the raster's cost).
        let mut t = Vec::new();
        for (name, ms) in [("gbuffer", raster - 1.0), ("visibility trace", traced), ("gbuffer resolve", 1.0)]
        {
            if !c.leaves_out(name) {
                t.push((name, ms));
            }
        }
        let n = match r {
            Recording::Both => 3,
            Recording::One(Technique::Raster) => 2,
            Recording::One(Technique::Traced) => 1,
        };
        assert_eq!(t.len(), n, "{r:?}: {t:?}");
        c.after_frame(&t);
        r
    }

    /// `n` probe frames.
    fn both(n: u32) -> Vec<Recording> {
        vec![Recording::Both; n as usize]
    }

    #[test]
    fn auto_probes_both_skips_cold_frames_and_keeps_the_cheaper() {
        use Recording::*;
        use Technique::*;
        let k = PROBE_SAMPLES;
        let mut c = Chooser::default();
        c.passes_rebuilt(&hybrid_auto());
        let o = Vec3::ZERO;
        // A cold probe, k measured ones, then traced.
        let seq: Vec<_> = (0..k + 3).map(|_| frame(&mut c, o, 20.0, 5.0)).collect();
        assert_eq!(seq, [both(k + 1), vec![One(Traced); 2]].concat());
        assert_eq!(c.last, Some((Traced, 20.0, 5.0)));
        // A small move keeps the choice; so does a large one within
        // MIN_PROBE_INTERVAL frames of the probe.
        assert_eq!(frame(&mut c, Vec3::new(0.5, 0.0, 0.0), 2.0, 5.0), One(Traced));
        while c.frames < MIN_PROBE_INTERVAL {
            assert_eq!(frame(&mut c, Vec3::new(5.0, 0.0, 0.0), 2.0, 5.0), One(Traced));
        }
        // After it, the large move probes again (the passes are warm now):
        // raster is cheaper at the new view.
        let seq: Vec<_> = (0..k + 1).map(|_| frame(&mut c, Vec3::new(5.0, 0.0, 0.0), 2.0, 5.0)).collect();
        assert_eq!(seq, [both(k), vec![One(Raster)]].concat());
        // Near-equal costs keep the technique in use (raster here): traced
        // at 0.85x of raster is within one probe's noise.
        c.chosen = None;
        c.passes_rebuilt(&hybrid_auto());
        let seq: Vec<_> = (0..k + 2).map(|_| frame(&mut c, Vec3::new(5.0, 0.0, 0.0), 10.0, 8.5)).collect();
        assert_eq!(seq, [both(k + 1), vec![One(Raster)]].concat());
        // A probe finishes while the camera keeps moving (else a moving
        // camera would never be measured); rebuilt passes are cold again.
        c.chosen = None;
        c.passes_rebuilt(&hybrid_auto());
        let seq: Vec<_> =
            (0..k + 2).map(|i| frame(&mut c, Vec3::new(5.0 * i as f32, 0.0, 0.0), 9.0, 1.0)).collect();
        assert_eq!(seq, [both(k + 1), vec![One(Traced)]].concat());
        // A still view is probed again after REPROBE_FRAMES frames.
        let p = Vec3::new(100.0, 0.0, 0.0);
        c.chosen = None;
        assert_eq!((0..k).map(|_| frame(&mut c, p, 9.0, 1.0)).collect::<Vec<_>>(), both(k));
        let seq: Vec<_> = (0..REPROBE_FRAMES + k + 1).map(|_| frame(&mut c, p, 9.0, 1.0)).collect();
        assert_eq!(seq.iter().position(|r| *r == Both), Some(REPROBE_FRAMES as usize));
        assert_eq!(seq.iter().filter(|r| **r == Both).count(), k as usize);
    }

    /// Each pass's cost is its least time over the probe's frames: frames
    /// where the raster read high (other work on the cores) do not switch
    /// a view whose raster is cheaper to camera rays (its first, last or
    /// mean sample would).
    #[test]
    fn slow_probe_frames_do_not_flip_the_choice() {
        let mut c = Chooser::default();
        c.passes_rebuilt(&hybrid_auto());
        let o = Vec3::ZERO;
        assert_eq!(frame(&mut c, o, 100.0, 100.0), Recording::Both); // cold
        let mut raster = [60.0, 27.0, 60.0].into_iter().chain(std::iter::repeat(27.0));
        for _ in 0..PROBE_SAMPLES {
            assert_eq!(frame(&mut c, o, raster.next().unwrap(), 30.0), Recording::Both);
        }
        assert_eq!(frame(&mut c, o, 27.0, 30.0), Recording::One(Technique::Raster));
        assert_eq!(c.last, Some((Technique::Raster, 27.0, 30.0)));
    }

    #[test]
    fn fixed_choices_and_pure_rt_do_not_choose() {
        for config in [
            ShadingConfig { visibility: PrimaryVisibility::Raster, ..hybrid_auto() },
            ShadingConfig { visibility: PrimaryVisibility::Traced, ..hybrid_auto() },
            ShadingConfig { mode: Mode::Rt, ..hybrid_auto() },
        ] {
            let mut c = Chooser::default();
            c.passes_rebuilt(&config);
            assert_eq!(c.choose(Vec3::ZERO, Vec3::NEG_Z, 1.0), None);
            assert!(!c.leaves_out("gbuffer") && !c.leaves_out("visibility trace"));
        }
        let s = RenderSettings::default();
        assert_eq!(effective(&s, false).primary_visibility, PrimaryVisibility::Raster);
        assert_eq!(effective(&s, true).primary_visibility, PrimaryVisibility::Auto);
    }
}
