//! `--primary-visibility auto`: the hybrid frame's primary hits come from the raster visibility buffer
//! (pass `gbuffer`) or camera rays (pass `visibility_trace`), whichever GPU timestamps say is cheaper
//! for the view. Neither always wins: on lavapipe the aa_edges scene's few large triangles rasterize
//! cheaper, while Sponza's raster (+ resolve) costs ~1.6x its camera rays and the armadillo's 345k small
//! triangles ~3x (bench/results/lavapipe-2core-vm-raster.md); on an H200 the raster costs ~2x on Sponza
//! (bench/results/h200-1080p.md). Both passes write the same hit ids.
//!
//! A probe records `PROBE_SAMPLES` frames of the technique in use (frames it renders anyway), then as
//! many of the other; a pass's cost is its least sample. So no frame pays for both passes (an earlier
//! version did, adding the slower pass to every probe frame). A pass's first frame is not counted (a
//! software device compiles its shaders there). The view is probed again after a large turn or move
//! (unless one pass cost `STABLE_MARGIN` times the other) and every `REPROBE_FRAMES` frames. A sample's
//! technique is read off the frame's own timings: the viewer's arrive frames late.

use glam::Vec3;

use super::settings::{PrimaryVisibility, RenderSettings};
use super::shading::{Mode, ShadingConfig};
use crate::scene::{Aabb, Camera};

pub use super::passes::Technique;

/// Frames after which a still view is measured again.
pub const REPROBE_FRAMES: u32 = 300;
/// A probe costs frames of the slower technique: at most one probe in this
/// many frames, however fast the camera moves.
pub const MIN_PROBE_INTERVAL: u32 = 30;
/// Probe frames per decision. One frame is a noisy sample (shared 2-core lavapipe: Sponza's raster probe
/// read 27-73 ms against ~30 ms steady); other load only adds time, so the least of a few is steadier.
pub const PROBE_SAMPLES: u32 = 3;
/// The technique in use (raster before any decision) is kept unless the other costs less than this
/// fraction of it, so near-equal costs do not flip the choice.
pub const SWITCH_BELOW: f64 = 0.8;
/// Frames from a fresh renderer until the first probe has decided: the raster's cold frame and samples,
/// then the traced pass's. A benchmark warms up at least this long, so neither pass's first frame (a
/// software device's shader compile) nor the probe's slower-technique frames land in measured ones.
pub const FRAMES_TO_WARM_BOTH: u32 = 2 * (PROBE_SAMPLES + 1);
/// A decision where one pass cost this many times the other is re-measured only every REPROBE_FRAMES
/// frames, not on view changes: such a margin rarely turns, and each probe costs slower-pass frames
/// (on lavapipe, Sponza's raster at 2.5x its camera rays re-probed every 30 frames along its path).
pub const STABLE_MARGIN: f64 = 2.0;
/// A camera turn since the measurement (radians, ~20 degrees) that triggers a new one.
const REPROBE_TURN: f32 = 0.35;
/// A camera move since the measurement (fraction of the scene's box diagonal) that triggers a new one.
const REPROBE_MOVE: f32 = 0.1;

/// `settings` as a renderer that does (`measure`) or does not measure sees them: without measuring auto
/// is what `model` says (a function of the scene's and frame's size, never of timing), so `render`,
/// tests and golden images never depend on timing.
pub fn effective(
    settings: &RenderSettings,
    measure: bool,
    model: impl FnOnce() -> PrimaryVisibility,
) -> RenderSettings {
    match settings.primary_visibility {
        PrimaryVisibility::Auto if !measure => RenderSettings { primary_visibility: model(), ..*settings },
        _ => *settings,
    }
}

/// What a frame rasterizes, for [`model`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterLoad {
    pub triangles: u64,
    pub draws: u64,
    pub pixels: u64,
}

/// A draw's fixed cost on lavapipe in triangles' worth: ~3 us a draw against ~90 ns a triangle
/// (bench/results/scale.md: 10,000 and 100,000 instances of a 12-triangle box).
pub const MODEL_TRIANGLES_PER_DRAW: u64 = 32;
/// The raster's load per pixel above which camera rays through the compute BVH cost less on a software
/// device: measured crossings between 1.7 and 5.2 (320x180) and between 3.3 and 10.9 (1280x720) triangles
/// per pixel on generated terrains (bench/results/scale.md).
pub const MODEL_TRACED_PER_PIXEL: u64 = 4;
/// ... and only at scale: below this load (triangles plus the draws' worth) lavapipe rasterizes a frame in
/// under ~0.1 s, so the model would save tens of ms while changing the images of ordinary scenes: the
/// techniques differ slightly at alpha-tested and silhouette pixels (Sponza's plants: texture LOD from
/// ray cones against raster derivatives), beyond the shipped goldens' bounds. The viewer and `bench`
/// measure per view at any size.
pub const MODEL_MIN_LOAD: u64 = 1 << 20;

impl RasterLoad {
    /// Triangles plus the draws' fixed cost.
    pub fn load(&self) -> u64 {
        self.triangles + MODEL_TRIANGLES_PER_DRAW * self.draws
    }

    /// [`RasterLoad::load`] per pixel.
    pub fn per_pixel(&self) -> f64 {
        self.load() as f64 / self.pixels.max(1) as f64
    }
}

/// Auto's choice where nothing is measured: traced where a CPU rasterizes (`software`) and the compute BVH
/// traces the frame anyway (`compute`), once the raster's load passes [`MODEL_MIN_LOAD`] and
/// [`MODEL_TRACED_PER_PIXEL`]; raster
/// otherwise (a GPU's rasterizer keeps up with any of these loads; lavapipe's ray queries only
/// overtake it at ~50 triangles per pixel).
pub fn model(load: RasterLoad, software: bool, compute: bool) -> PrimaryVisibility {
    let dense = load.load() >= MODEL_MIN_LOAD && load.per_pixel() >= MODEL_TRACED_PER_PIXEL as f64;
    if software && compute && dense {
        PrimaryVisibility::Traced
    } else {
        PrimaryVisibility::Raster
    }
}

/// What a frame records under auto: one technique, as a probe sample or as the one chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recording {
    Probe(Technique),
    One(Technique),
}

impl Recording {
    pub fn technique(self) -> Technique {
        match self {
            Recording::Probe(t) | Recording::One(t) => t,
        }
    }
}

/// The per-view choice under auto (unused otherwise).
#[derive(Debug, Default)]
pub struct Chooser {
    /// Auto measures only when set (the viewer, `bench`); otherwise it is raster (`effective`).
    pub measure: bool,
    /// Whether the frame's configuration chooses at all (hybrid, auto).
    active: bool,
    /// By Technique::index: the pass has run once since it was created (shaders compiled).
    warm: [bool; 2],
    /// What the prepared frame records (None: not choosing).
    recording: Option<Recording>,
    /// The technique kept and the probe times (raster, traced) that chose it (None: probing).
    chosen: Option<(Technique, f64, f64)>,
    /// The last decision, kept across probes (for `bench`).
    last: Option<(Technique, f64, f64)>,
    /// Frames since the last decision.
    frames: u32,
    /// The probe under way, by Technique::index: warm samples taken and the least time so far.
    samples: [(u32, f64); 2],
    /// Camera position and forward direction of the last probe.
    view: Option<(Vec3, Vec3)>,
}

impl Chooser {
    /// The passes were (re)made for `config`: both are cold again.
    pub fn passes_rebuilt(&mut self, config: &ShadingConfig) {
        self.active = config.mode == Mode::Hybrid && config.visibility == PrimaryVisibility::Auto;
        self.warm = [false; 2];
        self.samples = Default::default();
    }

    /// Before a frame of `config` seen by `camera` in a scene within `bounds`: whether it rasterizes
    /// (needs the G-buffer draw list).
    pub fn before_frame(&mut self, camera: &Camera, bounds: &Aabb, config: Option<ShadingConfig>) -> bool {
        let size = (bounds.max - bounds.min).length();
        let choice = self.choose(camera.position(), camera.forward(), size);
        config.is_some_and(|c| c.mode == Mode::Hybrid && !c.visibility.is_traced())
            && choice.map(Recording::technique) != Some(Technique::Traced)
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
        let wide = self.chosen.is_some_and(|(_, r, t)| r.max(t) >= STABLE_MARGIN * r.min(t));
        let due = changed && !wide && self.frames >= MIN_PROBE_INTERVAL || self.frames >= REPROBE_FRAMES;
        if self.chosen.is_some() && due {
            log::debug!("primary visibility: measuring again (view changed, or {REPROBE_FRAMES} frames)");
            self.chosen = None;
            self.samples = Default::default();
        }
        if self.chosen.is_none() {
            self.view = Some((position, forward));
        }
        let r = match self.chosen {
            Some((t, ..)) => Recording::One(t),
            None => {
                // The technique in use until its samples are in, then the other.
                let first = self.last.map_or(Technique::Raster, |(t, ..)| t);
                let done = self.samples[first.index()].0 >= PROBE_SAMPLES;
                Recording::Probe(if done { first.other() } else { first })
            }
        };
        self.recording = Some(r);
        Some(r)
    }

    /// The technique the prepared frame records (None: not auto, or not
    /// hybrid; the passes' `this_frame` read it).
    pub fn technique(&self) -> Option<Technique> {
        self.recording.map(Recording::technique)
    }

    /// After a frame completed, with its GPU pass times (possibly from a frame before the last prepared).
    pub fn after_frame(&mut self, timings: &[(&'static str, f64)]) {
        if self.recording.is_none() {
            return;
        }
        self.frames += 1;
        let ms = |name: &str| timings.iter().find(|(n, _)| *n == name).map(|(_, ms)| *ms);
        // The frame's technique: the one of the two passes that ran. The
        // raster's hits need the resolve pass; the traced pass resolves its own.
        let (t, time) = match (ms(Technique::Raster.pass()), ms(Technique::Traced.pass())) {
            (Some(r), None) => {
                (Technique::Raster, r + ms(super::passes::gbuffer_resolve::PASS.name).unwrap_or(0.0))
            }
            (None, Some(tr)) => (Technique::Traced, tr),
            _ => return,
        };
        if !std::mem::replace(&mut self.warm[t.index()], true) || self.chosen.is_some() {
            return; // compile time, not the pass's cost; or no probe under way
        }
        let (n, least) = self.samples[t.index()];
        self.samples[t.index()] = (n + 1, if n == 0 { time } else { least.min(time) });
        let [(nr, raster), (nt, traced)] = self.samples;
        if nr < PROBE_SAMPLES || nt < PROBE_SAMPLES {
            return;
        }
        self.samples = Default::default();
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

    /// For `bench`: what the last frame recorded and the last probe's times (None when not choosing).
    pub fn describe(&self) -> Option<String> {
        let what = match self.recording? {
            Recording::Probe(t) => format!("{} (a probe)", t.name()),
            Recording::One(t) => t.name().to_string(),
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
    use crate::render::passes::{gbuffer, gbuffer_resolve, visibility_trace, FrameState};

    fn hybrid_auto() -> ShadingConfig {
        let needs = super::super::shading::SceneNeeds {
            shadows: false,
            reflections: false,
            mirrors: false,
            glossy: false,
            refractions: false,
            shadow_maps: false,
            ambient_occluders: false,
            emitters: false,
            scene_ambient: None,
            scene_exposure: None,
            largest_primitive_triangles: 1,
            instances: 1,
        };
        ShadingConfig {
            inject: false,
            mode: Mode::Hybrid,
            effects: super::super::shading::Effects::NONE,
            backend: None,
            debug_view: false,
            needs,
            luminance: false,
            budget: false,
            shadow_fallback: false,
            aa: super::super::shading::AaMode::None,
            edge_aa_tiled: true,
            reference: false,
            terms: false,
            visibility: PrimaryVisibility::Auto,
            occlusion: false,
            glossy_temporal: false,
            ambient_visibility: false,
            ao_emitter_specular: false,
        }
    }

    /// One frame at `pos`; the raster costs `raster` ms (gbuffer and its
    /// 1-ms resolve), the traced pass `traced` ms.
    fn frame(c: &mut Chooser, pos: Vec3, raster: f64, traced: f64) -> Recording {
        let r = c.choose(pos, Vec3::NEG_Z, 10.0).unwrap();
        let mut t = Vec::new();
        let state = FrameState { visibility: c.technique(), ..Default::default() };
        let passes = [
            (&gbuffer::PASS, raster - 1.0),
            (&visibility_trace::PASS, traced),
            (&gbuffer_resolve::PASS, 1.0),
        ];
        for (pass, ms) in passes {
            if (pass.this_frame)(&state).is_none() {
                t.push((pass.name, ms));
            }
        }
        let n = match r.technique() {
            Technique::Raster => 2,
            Technique::Traced => 1,
        };
        assert_eq!(t.len(), n, "{r:?}: {t:?}");
        c.after_frame(&t);
        r
    }

    /// `n` probe frames of `t`.
    fn probe(t: Technique, n: u32) -> Vec<Recording> {
        vec![Recording::Probe(t); n as usize]
    }

    #[test]
    fn auto_probes_one_pass_per_frame_skips_cold_frames_and_keeps_the_cheaper() {
        use Recording::*;
        use Technique::*;
        let k = PROBE_SAMPLES;
        let mut c = Chooser::default();
        c.passes_rebuilt(&hybrid_auto());
        let o = Vec3::ZERO;
        // The raster (in use before any decision): a cold frame and k
        // samples; then the traced pass likewise; then traced is kept.
        let mut seq: Vec<_> = (0..FRAMES_TO_WARM_BOTH).map(|_| frame(&mut c, o, 8.0, 5.0)).collect();
        // What `bench` warms up for: both passes have run their cold frame, the probe has decided.
        assert!(c.warm == [true, true] && c.last.is_some(), "after FRAMES_TO_WARM_BOTH frames");
        seq.extend((0..2).map(|_| frame(&mut c, o, 8.0, 5.0)));
        assert_eq!(seq, [probe(Raster, k + 1), probe(Traced, k + 1), vec![One(Traced); 2]].concat());
        assert_eq!(c.last, Some((Traced, 8.0, 5.0)));
        // A small move keeps the choice; so does a large one within MIN_PROBE_INTERVAL frames of the probe.
        assert_eq!(frame(&mut c, Vec3::new(0.5, 0.0, 0.0), 2.0, 5.0), One(Traced));
        while c.frames < MIN_PROBE_INTERVAL {
            assert_eq!(frame(&mut c, Vec3::new(5.0, 0.0, 0.0), 2.0, 5.0), One(Traced));
        }
        // After it, the large move probes again, the technique in use
        // first (the passes are warm now): raster is cheaper at the new view.
        let seq: Vec<_> = (0..2 * k + 1).map(|_| frame(&mut c, Vec3::new(5.0, 0.0, 0.0), 2.0, 5.0)).collect();
        assert_eq!(seq, [probe(Traced, k), probe(Raster, k), vec![One(Raster)]].concat());
        // Near-equal costs keep the technique in use (raster here): traced
        // at 0.85x of raster is within one probe's noise.
        c.chosen = None;
        c.passes_rebuilt(&hybrid_auto());
        let seq: Vec<_> =
            (0..2 * k + 3).map(|_| frame(&mut c, Vec3::new(5.0, 0.0, 0.0), 10.0, 8.5)).collect();
        assert_eq!(seq, [probe(Raster, k + 1), probe(Traced, k + 1), vec![One(Raster)]].concat());
        // A probe finishes while the camera keeps moving (else a moving
        // camera would never be measured); rebuilt passes are cold again.
        c.chosen = None;
        c.passes_rebuilt(&hybrid_auto());
        let seq: Vec<_> =
            (0..2 * k + 3).map(|i| frame(&mut c, Vec3::new(5.0 * i as f32, 0.0, 0.0), 9.0, 1.0)).collect();
        assert_eq!(seq, [probe(Raster, k + 1), probe(Traced, k + 1), vec![One(Traced)]].concat());
        // A decision by a wide margin (9 vs 1 ms) is not measured again
        // when the view changes, only after REPROBE_FRAMES frames.
        c.frames = 0;
        let far = Vec3::new(50.0, 0.0, 0.0);
        for _ in 0..2 * MIN_PROBE_INTERVAL {
            assert_eq!(frame(&mut c, far, 9.0, 1.0), One(Traced));
        }
        // A still view is probed again after REPROBE_FRAMES frames: k frames
        // of the technique in use, k of the other.
        let p = Vec3::new(100.0, 0.0, 0.0);
        c.chosen = None;
        let seq: Vec<_> = (0..2 * k).map(|_| frame(&mut c, p, 9.0, 1.0)).collect();
        assert_eq!(seq, [probe(Traced, k), probe(Raster, k)].concat());
        let seq: Vec<_> = (0..REPROBE_FRAMES + 2 * k + 1).map(|_| frame(&mut c, p, 9.0, 1.0)).collect();
        let probes = |t| seq.iter().filter(|r| **r == Probe(t)).count();
        assert_eq!(seq.iter().position(|r| matches!(r, Probe(_))), Some(REPROBE_FRAMES as usize));
        assert_eq!((probes(Traced), probes(Raster)), (k as usize, k as usize));
    }

    /// The viewer's timings arrive frames late: a sample counts for the
    /// technique whose pass ran in that frame, not the one prepared last.
    #[test]
    fn late_timings_count_for_the_pass_that_ran() {
        let mut c = Chooser::default();
        c.passes_rebuilt(&hybrid_auto());
        let raster = [("gbuffer", 4.0), ("gbuffer resolve", 1.0)];
        let traced = [("visibility trace", 20.0)];
        // Frames prepared: raster x (k + 1), traced x (k + 1); the timings of each arrive two frames later.
        let mut pending = std::collections::VecDeque::new();
        for i in 0..2 * (PROBE_SAMPLES + 1) + 2 {
            let r = c.choose(Vec3::ZERO, Vec3::NEG_Z, 10.0).unwrap();
            pending.push_back(match r.technique() {
                Technique::Raster => raster.to_vec(),
                Technique::Traced => traced.to_vec(),
            });
            if i >= 2 {
                c.after_frame(&pending.pop_front().unwrap());
            }
        }
        while let Some(t) = pending.pop_front() {
            c.after_frame(&t);
        }
        // (Attributed to the technique prepared last, the raster's late
        // samples would read as traced ones: traced 5 ms.)
        assert_eq!(c.last, Some((Technique::Raster, 5.0, 20.0)));
    }

    /// Each pass's cost is its least time over the probe's frames: frames where the raster read high (other
    /// work on the cores) do not switch a view whose raster is cheaper to camera rays (its first, last or
    /// mean sample would).
    #[test]
    fn slow_probe_frames_do_not_flip_the_choice() {
        let mut c = Chooser::default();
        c.passes_rebuilt(&hybrid_auto());
        let o = Vec3::ZERO;
        use Technique::*;
        let mut raster = [100.0, 60.0, 27.0, 60.0].into_iter(); // the first frame is cold
        for _ in 0..=PROBE_SAMPLES {
            assert_eq!(frame(&mut c, o, raster.next().unwrap(), 100.0), Recording::Probe(Raster));
        }
        for _ in 0..=PROBE_SAMPLES {
            assert_eq!(frame(&mut c, o, 27.0, 30.0), Recording::Probe(Traced));
        }
        assert_eq!(frame(&mut c, o, 27.0, 30.0), Recording::One(Raster));
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
            assert_eq!(c.technique(), None, "no technique chosen: every pass records");
        }
        let s = RenderSettings::default();
        let raster = || PrimaryVisibility::Raster;
        assert_eq!(effective(&s, false, raster).primary_visibility, PrimaryVisibility::Raster);
        assert_eq!(effective(&s, true, raster).primary_visibility, PrimaryVisibility::Auto);
        let traced = || PrimaryVisibility::Traced;
        assert_eq!(effective(&s, false, traced).primary_visibility, PrimaryVisibility::Traced);
        let fixed = RenderSettings { primary_visibility: PrimaryVisibility::Raster, ..s };
        assert_eq!(effective(&fixed, false, traced).primary_visibility, PrimaryVisibility::Raster);
    }

    #[test]
    fn the_model_traces_only_dense_frames_on_a_software_device_with_the_compute_tracer() {
        let px = 1 << 18;
        let load = |triangles: u64, draws: u64| RasterLoad { triangles, draws, pixels: px };
        use PrimaryVisibility::{Raster, Traced};
        // 4 triangles per pixel is the line; draws count 32 triangles each.
        assert_eq!(model(load(4 * px - 1, 0), true, true), Raster);
        assert_eq!(model(load(4 * px, 0), true, true), Traced);
        assert_eq!(model(load(4 * px - 32, 1), true, true), Traced);
        assert_eq!(model(load(4 * px - 33, 1), true, true), Raster);
        // Dense but small: raster.
        let small = RasterLoad { triangles: MODEL_MIN_LOAD - 1, draws: 0, pixels: 1000 };
        assert_eq!(model(small, true, true), Raster);
        assert_eq!(model(RasterLoad { triangles: MODEL_MIN_LOAD, ..small }, true, true), Traced);
        // A GPU, or another tracer: raster.
        assert_eq!(model(load(1 << 30, 0), false, true), Raster);
        assert_eq!(model(load(1 << 30, 0), true, false), Raster);
        assert_eq!(RasterLoad { triangles: 1000, draws: 10, pixels: 1000 }.per_pixel(), 1.32);
    }
}
