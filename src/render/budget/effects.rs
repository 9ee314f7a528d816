//! Effects mode (`--budget-mode effects`, `--budget-ms T`): the paper's relevance, but selection per
//! (object, effect) — reflections without shadows, say — and costs in ms, so `T` is a real time budget
//! for `direct` + `specular`.
//!
//! Per ray stage (shadows in `direct`, reflection/refraction chains in `specular`):
//! `stage ms = base + k · rays`. Both are measured: `base` in a calibration frame with nothing
//! selected (the stage shades every pixel anyway), `k` from frames that traced rays. Rays per covered
//! pixel of an (object, effect) come from frames that traced it (`BUDGET_STAT_RAYS`), else the
//! paper's `Q` terms.
//!
//! Selection is the paper's greedy rule on (object, effect) pairs: cost `A · rays per pixel · k`,
//! relevance `(S·I + V)·K` with `S` per pair, within `T − base(direct) − base(specular)`. It corrects
//! itself: if `k` is off, the next frame's rays show it, and `rays → T/(ms per ray)` has the budget as
//! fixed point while the bases fit. `E` is unused: the cost is measured.
//!
//! The leftover budget goes to a partial pair: the most relevant reflection or refraction pair that did
//! not fit, traced on `left / cost` of its pixels, rounded down to whole ranks of an 8x8 ordered-dither
//! lattice (EFFECT_PARTIAL_SHIFT); `composite` interpolates the untraced pixels from the traced lattice
//! (glsl/common/budget_fill.glsl), so a share reads as a lower-resolution effect, not a pattern.
//! Otherwise the budget is met only in whole-object steps, and a scene whose cost sits in one object
//! (Sponza's building) gets all or nothing. Shadows are bought per whole object: `direct` traces them
//! per pixel, uncompacted, where a pixel-scale share diverges and saves little on SIMD hardware (8x8
//! tiles did, but read as a blocky pattern); the shadow maps are their fallback.

use super::paper::{self, ObjectStats, Scored, Screen};
use crate::gpu::shared::{
    BUDGET_LATTICE, EFFECT_ALL, EFFECT_BIT_REFLECTIONS, EFFECT_BIT_REFRACTIONS, EFFECT_BIT_SHADOWS,
    EFFECT_COUNT, EFFECT_FRACTION_SHIFT, EFFECT_PARTIAL_SHIFT,
};

pub const EFFECTS: usize = EFFECT_COUNT as usize;

/// The effects' names, by `EFFECT_BIT_*`.
pub const EFFECT_NAMES: [&str; EFFECTS] = ["shadows", "reflections", "refractions"];

/// The ray stages, by the passes that make them: shadows in `direct`; reflection / refraction chains in
/// `specular`, glossy reflections in `glossy` and their filter (a cost of having the effect at all).
pub const STAGES: [&[&str]; 2] = [&["direct"], &["specular", "glossy", "glossy temporal", "glossy filter"]];
/// The raster fallback's pass (render/passes/shadow_map.rs): its time counts against the budget too.
pub const SHADOW_MAP_PASS: &str = "shadow_map";

pub const fn stage_of(effect: usize) -> usize {
    if effect == EFFECT_BIT_SHADOWS as usize {
        0
    } else {
        1
    }
}

/// Weight of a new frame in the moving average of a stage's base.
const SMOOTHING: f64 = 0.3;
/// Median window for the time per ray: a spike in up to 3 of 7 frames leaves it alone, a real change
/// shows after 4.
const WINDOW: usize = 7;

/// One ray stage's `ms = base + k · rays`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageFit {
    /// The stage with nothing traced (None until a frame traced nothing).
    pub base_ms: Option<f64>,
    /// `(ms − base) / rays` of the last frames that traced rays (a ring).
    recent: [f64; WINDOW],
    /// Frames in `recent` (up to WINDOW) and the next slot to write.
    len: usize,
    next: usize,
}

impl StageFit {
    /// Lower median of the last WINDOW frames' time per ray (0 before any ray). Not a mean: on lavapipe
    /// about one frame in ten takes 1.5-2x as long for the same rays (another process mid-pass), and a
    /// mean following the spike undershoots the next selections for frames (a limit cycle around T).
    pub fn ms_per_ray(&self) -> f64 {
        if self.len == 0 {
            return 0.0;
        }
        let mut v = self.recent;
        let v = &mut v[..self.len];
        v.sort_by(|a, b| a.total_cmp(b));
        v[(self.len - 1) / 2]
    }

    fn observe(&mut self, ms: f64, rays: f64) {
        if !ms.is_finite() || ms < 0.0 {
            return;
        }
        if rays <= 0.0 {
            let b = self.base_ms.map_or(ms, |b| b + SMOOTHING * (ms - b));
            self.base_ms = Some(b);
            return;
        }
        let excess = (ms - self.base_ms.unwrap_or(0.0)).max(0.0);
        self.recent[self.next] = excess / rays;
        self.next = (self.next + 1) % WINDOW;
        self.len = (self.len + 1).min(WINDOW);
    }

    /// Predicted stage ms for `rays`.
    pub fn predict(&self, rays: f64) -> f64 {
        self.base_ms.unwrap_or(0.0) + self.ms_per_ray() * rays
    }
}

// glsl/common/scene.glsl's `budget_rank` is the 8x8 Bayer matrix.
const _: () = assert!(BUDGET_LATTICE == 8);
/// Ranks of the ordered-dither lattice: a share is a whole number of them.
const RANKS: u32 = BUDGET_LATTICE * BUDGET_LATTICE;

/// Pixels a partial pair must cover for its rays per pixel to be measured (fewer leave the lattice's
/// share of an object's pixels far from the word's).
const MIN_PARTIAL_PIXELS: f64 = 4.0 * RANKS as f64;

/// The budget mask's per-object word: `full` effects on every pixel, `partial` ones on `fraction` of
/// them, rounded down to whole lattice ranks (so never more than asked).
pub fn selection_word(full: u32, partial: u32, fraction: f64) -> u32 {
    let q = ((fraction.clamp(0.0, 1.0) * RANKS as f64).floor() as u32).min(RANKS);
    if partial == 0 || q == 0 {
        return full & EFFECT_ALL;
    }
    (full & EFFECT_ALL) | ((partial & EFFECT_ALL) << EFFECT_PARTIAL_SHIFT) | (q << EFFECT_FRACTION_SHIFT)
}

/// Share of its pixels on which `word` traces `effect`: 1, the word's ranks over all (each rank is one
/// pixel of every 8x8 block), or 0.
pub fn traced_fraction(word: u32, effect: usize) -> f64 {
    if (word >> effect) & 1 == 1 {
        1.0
    } else if (word >> (EFFECT_PARTIAL_SHIFT as usize + effect)) & 1 == 1 {
        (word >> EFFECT_FRACTION_SHIFT) as f64 / RANKS as f64
    } else {
        0.0
    }
}

/// What one finished frame showed the model.
pub struct Observation<'a> {
    /// Per object: the statistics words' pixels and rays per effect.
    pub pixels: &'a [u32],
    pub rays: &'a [[u32; EFFECTS]],
    /// Selection words each object traced ([`selection_word`]).
    pub traced: &'a [u32],
    /// GPU ms of `direct` and `specular` (0 when left out; None when not representative, e.g. a shader
    /// compiled on first use inside them).
    pub stage_ms: Option<[f64; 2]>,
    /// GPU ms of the `shadow_map` pass when it rendered (representative frames only).
    pub shadow_maps_ms: Option<f64>,
}

/// The measured cost model, kept across frames (and budgets).
#[derive(Clone, Debug, Default)]
pub struct CostModel {
    pub stages: [StageFit; 2],
    /// Per object and effect: rays per covered pixel when last traced.
    rays_per_pixel: Vec<[Option<f64>; EFFECTS]>,
    /// A frame that traced every effect of every object has been seen.
    seen_full: bool,
    /// The raster fallback's shadow maps (moving average; None until they rendered in a measured frame).
    shadow_maps: Option<f64>,
}

impl CostModel {
    /// Both calibration frames seen: the empty one (bases) and the full one (rays per pixel, `k`).
    pub fn calibrated(&self) -> bool {
        self.seen_full && self.stages.iter().all(|s| s.base_ms.is_some())
    }

    /// Nothing traced (for the bases), then everything.
    pub fn calibration_mask(&self) -> u32 {
        if self.stages.iter().any(|s| s.base_ms.is_none()) {
            0
        } else {
            crate::gpu::shared::EFFECT_ALL
        }
    }

    pub fn observe(&mut self, o: &Observation) {
        let mut stage_rays = [0.0f64; 2];
        if self.rays_per_pixel.len() < o.pixels.len() {
            self.rays_per_pixel.resize(o.pixels.len(), [None; EFFECTS]);
        }
        let mut all_traced = true;
        for (i, &pixels) in o.pixels.iter().enumerate() {
            let traced = o.traced.get(i).copied().unwrap_or(0);
            let rays = o.rays.get(i).copied().unwrap_or([0; EFFECTS]);
            for e in 0..EFFECTS {
                stage_rays[stage_of(e)] += rays[e] as f64;
                let share = traced_fraction(traced, e);
                if share < 1.0 {
                    all_traced &= pixels == 0;
                }
                let traced_pixels = share * pixels as f64;
                if share >= 1.0 && pixels > 0 || traced_pixels >= MIN_PARTIAL_PIXELS {
                    self.rays_per_pixel[i][e] = Some(rays[e] as f64 / traced_pixels);
                }
            }
        }
        if let Some(ms) = o.shadow_maps_ms.filter(|ms| ms.is_finite() && *ms >= 0.0) {
            self.shadow_maps = Some(self.shadow_maps.map_or(ms, |m| m + SMOOTHING * (ms - m)));
        }
        let Some(stage_ms) = o.stage_ms else { return };
        for (s, fit) in self.stages.iter_mut().enumerate() {
            // A stage that traced no ray shows its base.
            fit.observe(stage_ms[s], stage_rays[s]);
        }
        self.seen_full |= all_traced && o.pixels.iter().any(|&p| p > 0);
    }

    /// What the raster fallback's shadow maps cost a frame: measured, else 0 (the first calibration
    /// frame, which traces nothing, renders and measures them).
    pub fn shadow_maps_ms(&self) -> f64 {
        self.shadow_maps.unwrap_or(0.0)
    }

    /// Measured, else the paper's estimate for that effect.
    pub fn rays_per_pixel(&self, object: usize, effect: usize, estimate: f64) -> f64 {
        self.rays_per_pixel.get(object).and_then(|r| r[effect]).unwrap_or(estimate)
    }
}

/// The paper's `Q` split by effect: shadow-casting lights for shadows, `lights + 1` for reflections,
/// `lights + 4` for refractions; 0 for an effect the object cannot have.
pub fn estimated_rays(o: &ObjectStats, shadow_lights: u32, lights: u32) -> [f64; EFFECTS] {
    let mut q = [0.0; EFFECTS];
    q[EFFECT_BIT_SHADOWS as usize] = shadow_lights as f64;
    if o.reflective {
        q[EFFECT_BIT_REFLECTIONS as usize] = lights as f64 + 1.0;
    }
    if o.refractive {
        q[EFFECT_BIT_REFRACTIONS as usize] = lights as f64 + 4.0;
    }
    q
}

/// What effects mode chose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EffectsSelection {
    /// Per object: EFFECT_* bits traced on every pixel, plus the partial pair ([`selection_word`]).
    pub bits: Vec<u32>,
    /// The partial pair: object, effect, fraction of its pixels.
    pub partial: Option<(usize, usize, f64)>,
    /// Predicted rays of each ray stage (`direct`, `specular`).
    pub predicted_rays: [f64; 2],
    /// Predicted ms of the ray stages with this selection (bases included), and of the shadow maps when
    /// they render.
    pub predicted_ms: f64,
    /// The bases alone (what any selection costs).
    pub base_ms: f64,
    /// The raster fallback's shadow maps render: the selection leaves shadows out, and the maps cost
    /// less than tracing those shadows would and fit the budget.
    pub shadow_maps: bool,
}

/// The (object, effect) pairs that could be traced, with their costs and rays.
struct Pairs {
    scored: Vec<Scored>,
    rays: Vec<f64>,
    objects: usize,
}

/// One greedy pick within `left` ms: the pairs `forced` says first, then the paper's rule, then the
/// leftover as a share of the most relevant pair that did not fit.
struct Pick {
    bits: Vec<u32>,
    partial: Option<(usize, f64)>,
    predicted_rays: [f64; 2],
    spent: f64,
}

impl Pairs {
    fn effect(&self, i: usize) -> usize {
        self.scored[i].object % EFFECTS
    }

    fn pick(&self, left: f64, forced: impl Fn(usize) -> bool) -> Pick {
        let mut pick =
            Pick { bits: vec![0; self.objects], partial: None, predicted_rays: [0.0; 2], spent: 0.0 };
        let mut taken = vec![false; self.scored.len()];
        let take = |pick: &mut Pick, i: usize, share: f64| {
            let (o, e) = (self.scored[i].object / EFFECTS, self.effect(i));
            let word = &mut pick.bits[o];
            *word = if share >= 1.0 { *word | 1 << e } else { selection_word(*word, 1 << e, share) };
            let share = traced_fraction(*word, e);
            pick.predicted_rays[stage_of(e)] += share * self.rays[i];
            pick.spent += share * self.scored[i].cost;
        };
        for i in (0..self.scored.len()).filter(|&i| forced(i)) {
            take(&mut pick, i, 1.0);
            taken[i] = true;
        }
        let rest: Vec<Scored> =
            self.scored.iter().zip(&taken).filter(|(_, t)| !**t).map(|(p, _)| *p).collect();
        let chosen = paper::select(&rest, left - pick.spent);
        let in_rest = |i: usize| chosen.mask.get(self.scored[i].object).copied().unwrap_or(false);
        let rest_taken: Vec<usize> = (0..taken.len()).filter(|&i| !taken[i] && in_rest(i)).collect();
        for i in rest_taken {
            take(&mut pick, i, 1.0);
        }
        let chosen_pair = |i: usize| taken[i] || in_rest(i);
        let left = left - pick.spent;
        let shareable = |i: usize| self.effect(i) != EFFECT_BIT_SHADOWS as usize;
        let partial = (0..self.scored.len())
            .filter(|&i| paper::candidate(&self.scored[i]) && self.scored[i].cost > 0.0 && !chosen_pair(i))
            .filter(|&i| shareable(i))
            .min_by(|&a, &b| paper::rank(&self.scored[a], &self.scored[b]))
            .filter(|_| left.is_finite() && left > 0.0)
            // Whole ranks (a hair of slack so that a leftover of exactly n ranks is not n - 1).
            .map(|i| {
                (
                    i,
                    (left / self.scored[i].cost * RANKS as f64 + 1e-9).floor().min(RANKS as f64)
                        / RANKS as f64,
                )
            })
            .filter(|&(_, share)| share > 0.0);
        if let Some((i, share)) = partial {
            take(&mut pick, i, share);
        }
        pick.partial = partial;
        pick
    }

    /// What tracing the shadows `pick` leaves out would cost (ms).
    fn shadows_left_out(&self, pick: &Pick) -> f64 {
        self.shadows_ms(|p| 1.0 - traced_fraction(pick.bits[p.object / EFFECTS], EFFECT_BIT_SHADOWS as usize))
    }

    /// What tracing every shadow the heuristic may trace (relevance K > 0) would cost (ms).
    fn traceable_shadows(&self) -> f64 {
        self.shadows_ms(|p| if paper::candidate(p) { 1.0 } else { 0.0 })
    }

    /// The visible shadow pairs' cost (ms), each times `share(pair)`.
    fn shadows_ms(&self, share: impl Fn(&Scored) -> f64) -> f64 {
        (0..self.scored.len())
            .filter(|&i| self.effect(i) == EFFECT_BIT_SHADOWS as usize && self.scored[i].pixels > 0)
            .map(|i| share(&self.scored[i]) * self.scored[i].cost)
            .sum()
    }
}

/// Selects (object, effect) pairs within `budget_ms`; `previous` gives per-pair stickiness. With
/// `shadow_fallback` (`--fallback raster` and a light with a shadow map) the shadows left out are
/// rasterized from shadow maps, whose measured cost counts against the budget too: a selection that
/// leaves shadows out pays for the maps, and where tracing the shadows it leaves out costs no more than
/// the maps, it traces them instead. Maps that do not fit leave those shadows out with no fallback.
pub fn select(
    objects: &[ObjectStats],
    screen: Screen,
    params: &paper::Params,
    model: &CostModel,
    budget_ms: f64,
    previous: Option<&[u32]>,
    shadow_fallback: bool,
) -> EffectsSelection {
    // The paper's score gives V and K per object; cost and S are per pair.
    let scored = paper::score(objects, screen, params);
    let stickiness = if params.stickiness.is_finite() { params.stickiness as f64 } else { 0.0 };
    let k = [0usize, 1].map(|s| model.stages[s].ms_per_ray());
    let mut pairs = Pairs { scored: Vec::new(), rays: Vec::new(), objects: objects.len() };
    for (o, (stats, s)) in objects.iter().zip(&scored).enumerate() {
        let q = estimated_rays(stats, params.shadow_lights, params.lights);
        let relevance_factor = if stats.relevance.is_finite() { stats.relevance as f64 } else { 0.0 };
        for e in 0..EFFECTS {
            let rays = model.rays_per_pixel(o, e, q[e]);
            if q[e] <= 0.0 && rays <= 0.0 {
                continue; // nothing this object could trace for the effect
            }
            let sticky = previous.and_then(|p| p.get(o)).is_some_and(|b| (b >> e) & 1 == 1);
            let relevance = ((if sticky { stickiness } else { 0.0 }) + s.visibility) * relevance_factor;
            pairs.scored.push(Scored {
                object: o * EFFECTS + e,
                pixels: s.pixels,
                visibility: s.visibility,
                cost: s.pixels as f64 * rays * k[stage_of(e)],
                relevance,
            });
            pairs.rays.push(s.pixels as f64 * rays);
        }
    }
    let base_ms: f64 = model.stages.iter().map(|s| s.base_ms.unwrap_or(0.0)).sum();
    let left = budget_ms - base_ms;
    let mut pick = pairs.pick(left, |_| false);
    let mut shadow_maps = false;
    let mut maps_ms = 0.0;
    if shadow_fallback && pairs.shadows_left_out(&pick) > 0.0 {
        let maps = model.shadow_maps_ms();
        let with_maps = pairs.pick(left - maps, |_| false);
        let replaced = pairs.shadows_left_out(&with_maps);
        if maps <= left && replaced > maps {
            (pick, shadow_maps, maps_ms) = (with_maps, true, maps);
        } else if pairs.traceable_shadows() <= left {
            // The maps cost more than the rays they replace, or do not fit: trace every shadow that may
            // be traced (an object of relevance 0 stays unshadowed).
            let shadow = |i: usize| pairs.effect(i) == EFFECT_BIT_SHADOWS as usize;
            pick = pairs.pick(left, |i| shadow(i) && paper::candidate(&pairs.scored[i]));
        }
    }
    let partial = pick.partial.map(|(i, share)| (pairs.scored[i].object / EFFECTS, pairs.effect(i), share));
    EffectsSelection {
        bits: pick.bits,
        partial,
        predicted_rays: pick.predicted_rays,
        predicted_ms: base_ms + pick.spent + maps_ms,
        base_ms,
        shadow_maps,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj(pixels: u32, distance: f32, reflective: bool) -> ObjectStats {
        ObjectStats {
            pixels,
            bbox_min: [40.0, 40.0],
            bbox_max: [60.0, 60.0],
            distance,
            reflective,
            refractive: false,
            cost_factor: 1.0,
            relevance: 1.0,
            selected_last_frame: false,
        }
    }

    const SCREEN: Screen = Screen { width: 100, height: 100 };

    fn params(stickiness: f32) -> paper::Params {
        paper::Params { budget: 0.0, stickiness, shadow_lights: 1, lights: 1 }
    }

    /// Base 2 ms per stage, shadows 0.001 ms/ray, specular 0.01 ms/ray;
    /// 100 pixels per object, measured at 1 shadow ray and `refl` reflection
    /// rays per pixel.
    fn model(refl: &[u32]) -> CostModel {
        let objects = refl.len();
        let mut m = CostModel::default();
        let pixels = vec![100; objects];
        let none = vec![[0; EFFECTS]; objects];
        m.observe(&Observation {
            pixels: &pixels,
            rays: &none,
            traced: &vec![0; objects],
            stage_ms: Some([2.0, 2.0]),
            shadow_maps_ms: None,
        });
        assert!(!m.calibrated() && m.calibration_mask() == crate::gpu::shared::EFFECT_ALL);
        let rays: Vec<[u32; EFFECTS]> = refl.iter().map(|&r| [100, 100 * r, 0]).collect();
        let all = vec![crate::gpu::shared::EFFECT_ALL; objects];
        let refl_rays: u32 = refl.iter().sum::<u32>() * 100;
        let ms = [2.0 + 0.001 * 100.0 * objects as f64, 2.0 + 0.01 * refl_rays as f64];
        m.observe(&Observation {
            pixels: &pixels,
            rays: &rays,
            traced: &all,
            stage_ms: None,
            shadow_maps_ms: None,
        });
        assert!(!m.calibrated(), "a frame without representative times calibrates nothing");
        m.observe(&Observation {
            pixels: &pixels,
            rays: &rays,
            traced: &all,
            stage_ms: Some(ms),
            shadow_maps_ms: None,
        });
        assert!(m.calibrated());
        m
    }

    #[test]
    fn the_model_recovers_base_and_ms_per_ray() {
        let m = model(&[2, 2, 2]);
        assert_eq!(m.stages[0].base_ms, Some(2.0));
        assert!((m.stages[0].ms_per_ray() - 0.001).abs() < 1e-12);
        assert!((m.stages[1].ms_per_ray() - 0.01).abs() < 1e-12);
        assert!((m.stages[1].predict(200.0) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn spikes_leave_the_time_per_ray_alone_and_a_real_change_shows_within_the_window() {
        let mut m = model(&[2]);
        let k = m.stages[1].ms_per_ray();
        let frame = |m: &mut CostModel, per_ray: f64| {
            m.observe(&Observation {
                pixels: &[100],
                rays: &[[100, 200, 0]],
                traced: &[EFFECT_ALL],
                stage_ms: Some([2.1, 2.0 + 200.0 * per_ray]),
                shadow_maps_ms: None,
            })
        };
        for _ in 0..WINDOW {
            frame(&mut m, k);
        }
        // Three spikes of 100 times the usual time for the same rays, in a
        // window of 7: still k.
        for _ in 0..3 {
            frame(&mut m, 100.0 * k);
            assert!((m.stages[1].ms_per_ray() / k - 1.0).abs() < 1e-9, "{}", m.stages[1].ms_per_ray() / k);
        }
        // The cost really doubles: the estimate follows within the window.
        let mut followed = None;
        for i in 0..WINDOW {
            frame(&mut m, 2.0 * k);
            if (m.stages[1].ms_per_ray() / k - 1.0).abs() > 0.5 && followed.is_none() {
                followed = Some(i + 1);
            }
        }
        assert!(followed.is_some_and(|n| n <= 4), "k followed after {followed:?} frames");
        assert!((m.stages[1].ms_per_ray() / (2.0 * k) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn selection_is_per_effect_and_fits_the_budget() {
        // Costs: shadows 0.1 ms, reflections 2 ms per object (of 100 px).
        let objects = [obj(100, 1.0, true), obj(100, 2.0, true), obj(100, 4.0, false)];
        let m = model(&[2, 2, 0]);
        // Bases 4 ms; 2.35 ms left, in order of relevance: the nearest
        // object's shadows and reflections (2.1 ms), the second's shadows,
        // not its reflections (2 ms more), the third's shadows.
        // The 0.05 ms left go to the best pair that did not fit, the second
        // object's reflections, on 0.05 / 2 of its pixels, rounded down to
        // whole lattice ranks: 1 of 64.
        let s = select(&objects, SCREEN, &params(0.0), &m, 6.35, None, false);
        assert_eq!(s.bits.iter().map(|b| b & EFFECT_ALL).collect::<Vec<_>>(), vec![0b011, 0b001, 0b001]);
        let (o, e, share) = s.partial.expect("a partial pair");
        assert_eq!((o, e), (1, EFFECT_BIT_REFLECTIONS as usize));
        assert_eq!((share, traced_fraction(s.bits[1], e)), (1.0 / 64.0, 1.0 / 64.0));
        assert!((s.predicted_ms - (6.3 + 2.0 / 64.0)).abs() < 1e-9, "{}", s.predicted_ms);
        // With 0.5 ms left, a quarter: 16 ranks, T met exactly.
        let s = select(&objects, SCREEN, &params(0.0), &m, 6.8, None, false);
        assert_eq!(s.partial, Some((1, EFFECT_BIT_REFLECTIONS as usize, 0.25)));
        assert!((s.predicted_ms - 6.8).abs() < 1e-9, "{}", s.predicted_ms);
        // Rays: 3 objects' shadows (100 each), 2 reflections per pixel of
        // the first object and of a quarter of the second's.
        assert!((s.predicted_rays[0] - 300.0).abs() < 1e-9, "{:?}", s.predicted_rays);
        assert!((s.predicted_rays[1] - 250.0).abs() < 1e-9, "{:?}", s.predicted_rays);
        // Below the bases nothing; an unlimited budget everything possible.
        assert_eq!(select(&objects, SCREEN, &params(0.0), &m, 3.9, None, false).bits, vec![0; 3]);
        let all = select(&objects, SCREEN, &params(0.0), &m, f64::INFINITY, None, false);
        assert_eq!(all.bits, vec![0b011, 0b011, 0b001]);
        assert_eq!(all.partial, None, "nothing is left out of an unlimited budget");
    }

    #[test]
    fn the_budget_left_is_met_by_a_share_of_the_best_pair_that_did_not_fit() {
        // One object holds all the cost (2.1 ms): every budget between the
        // bases (4 ms) and everything is met, not just 4 and 6.1 ms.
        let objects = [obj(100, 1.0, true)];
        let m = model(&[2]);
        // Within one lattice rank of the reflections (2 ms / 64), never above.
        for t in [4.5, 5.0, 6.0] {
            let s = select(&objects, SCREEN, &params(0.0), &m, t, None, false);
            let under = t - s.predicted_ms;
            assert!((-1e-9..2.0 / 64.0).contains(&under), "T {t}: {}", s.predicted_ms);
        }
        // 4.5 ms: shadows (0.1 ms) fit; reflections (2 ms) get 0.4 / 2 = 12.8 ranks of 64: 12.
        let s = select(&objects, SCREEN, &params(0.0), &m, 4.5, None, false);
        assert_eq!(s.bits[0] & EFFECT_ALL, 0b001);
        assert_eq!(traced_fraction(s.bits[0], 1), 12.0 / 64.0);
        // Less than one rank left: no share.
        let s = select(&objects, SCREEN, &params(0.0), &m, 4.12, None, false);
        assert_eq!((s.bits[0], s.partial), (0b001, None));
        // Shadows get no share: an object whose only effect is its shadows (0.1 ms) is bought whole.
        let dull = [obj(100, 1.0, false)];
        let m1 = model(&[0]);
        let s = select(&dull, SCREEN, &params(0.0), &m1, 4.05, None, false);
        assert_eq!((s.bits[0], s.partial), (0, None));
        assert_eq!(select(&dull, SCREEN, &params(0.0), &m1, 4.2, None, false).bits[0], 0b001);
        // K = 0 gets no share either.
        let none = [ObjectStats { relevance: 0.0, ..objects[0] }];
        let s = select(&none, SCREEN, &params(0.0), &m, 5.0, None, false);
        assert_eq!((s.bits[0], s.partial), (0, None));
    }

    #[test]
    fn selection_words_round_trip_and_partial_pairs_are_measured_per_traced_pixel() {
        let w = selection_word(0b001, 0b100, 0.5);
        assert_eq!(w & EFFECT_ALL, 0b001);
        assert_eq!(traced_fraction(w, 0), 1.0);
        assert_eq!(traced_fraction(w, 1), 0.0);
        assert_eq!(traced_fraction(w, 2), 0.5);
        // Rounded down to whole ranks of 64; under one rank is no share.
        assert_eq!(traced_fraction(selection_word(0, 0b010, 0.999), 1), 63.0 / 64.0);
        assert_eq!(selection_word(0, 0b010, 0.5 / 64.0), 0);
        assert_eq!(selection_word(0b010, 0b001, 0.0), 0b010, "a zero share is no partial pair");
        assert_eq!(selection_word(0b010, 0, 0.7), 0b010);
        // Reflections traced on a quarter of 1000 pixels, 500 rays: 2 per
        // traced pixel (not 0.5 per pixel of the object).
        let mut m = model(&[2]);
        let word = selection_word(0b001, 0b010, 0.25);
        let share = traced_fraction(word, 1);
        m.observe(&Observation {
            pixels: &[1000],
            rays: &[[1000, (500.0 * share / 0.25).round() as u32, 0]],
            traced: &[word],
            stage_ms: Some([3.0, 7.0]),
            shadow_maps_ms: None,
        });
        assert!((m.rays_per_pixel(0, 1, 99.0) - 2.0).abs() < 1e-3, "{}", m.rays_per_pixel(0, 1, 99.0));
        // A share of too few pixels leaves the last measurement alone.
        let tiny = selection_word(0, 0b010, 0.01);
        m.observe(&Observation {
            pixels: &[1000],
            rays: &[[0, 7, 0]],
            traced: &[tiny],
            stage_ms: None,
            shadow_maps_ms: None,
        });
        assert!((m.rays_per_pixel(0, 1, 99.0) - 2.0).abs() < 1e-3);
    }

    #[test]
    fn stickiness_is_per_pair_and_k_zero_is_never_selected() {
        let mut objects = [obj(100, 1.0, true), obj(100, 1.0, true)];
        let m = model(&[2, 2]);
        // Equal objects, room for one reflection: without stickiness the
        // lower id; with it, the pair selected last frame.
        let p = params(1e3);
        let full = |s: EffectsSelection| s.bits.iter().map(|b| b & EFFECT_ALL).collect::<Vec<_>>();
        assert_eq!(full(select(&objects, SCREEN, &p, &m, 6.25, None, false)), vec![0b011, 0b001]);
        assert_eq!(
            full(select(&objects, SCREEN, &p, &m, 6.25, Some(&[0b001, 0b011]), false)),
            vec![0b001, 0b011]
        );
        objects[0].relevance = 0.0;
        assert_eq!(select(&objects, SCREEN, &p, &m, f64::INFINITY, None, false).bits, vec![0, 0b011]);
    }

    fn with_maps(mut m: CostModel, ms: f64) -> CostModel {
        m.observe(&Observation {
            pixels: &[],
            rays: &[],
            traced: &[],
            stage_ms: None,
            shadow_maps_ms: Some(ms),
        });
        assert_eq!(m.shadow_maps_ms(), ms);
        m
    }

    #[test]
    fn shadow_maps_count_against_the_budget_and_cost_no_more_than_the_rays_they_replace() {
        // Shadows 0.1 ms, reflections 2 ms per object, bases 4 ms; T = 6.15 leaves 2.15.
        let objects = [obj(100, 1.0, true), obj(100, 2.0, true), obj(100, 4.0, false)];
        let m = model(&[2, 2, 0]);
        let shadows = |s: &EffectsSelection| s.bits.iter().map(|b| b & 1).collect::<Vec<_>>();
        let p = params(0.0);
        // Without the fallback: the nearest object's shadows and reflections; the others' shadows out.
        let plain = select(&objects, SCREEN, &p, &m, 6.15, None, false);
        assert_eq!((shadows(&plain), plain.shadow_maps), (vec![1, 0, 0], false));
        // Maps of 0.01 ms replace the ~0.2 ms of shadow rays left out: bought, within T.
        let cheap = select(&objects, SCREEN, &p, &with_maps(m.clone(), 0.01), 6.15, None, true);
        assert_eq!((shadows(&cheap), cheap.shadow_maps), (vec![1, 0, 0], true));
        // 2.14 ms left after the maps: 2.1 for the nearest object, a rank of the second's reflections.
        assert!((cheap.predicted_ms - (6.1 + 2.0 / 64.0 + 0.01)).abs() < 1e-9, "{}", cheap.predicted_ms);
        // Maps of 0.5 ms cost more than tracing those shadows: every shadow traced, no maps, within T.
        let dear = select(&objects, SCREEN, &p, &with_maps(m.clone(), 0.5), 6.15, None, true);
        assert_eq!((shadows(&dear), dear.shadow_maps), (vec![1, 1, 1], false));
        assert!(dear.predicted_ms <= 6.15 + 1e-3, "{}", dear.predicted_ms);
        // Neither the maps (0.2 ms, less than the 0.3 ms of shadows left out) nor every shadow fit 0.15
        // ms: no maps, T kept.
        let tight = select(&objects, SCREEN, &p, &with_maps(m.clone(), 0.2), 4.15, None, true);
        assert!(!tight.shadow_maps && tight.predicted_ms <= 4.15 + 1e-3, "{tight:?}");
        // An object the heuristic never traces (K = 0) keeps no shadow when the maps are too dear; the
        // others' shadows are traced.
        let mut k0 = objects;
        k0[2].relevance = 0.0;
        let dear_k0 = select(&k0, SCREEN, &p, &with_maps(m.clone(), 0.5), 6.15, None, true);
        assert_eq!((shadows(&dear_k0), dear_k0.shadow_maps), (vec![1, 1, 0], false));
        // Its shadows are left out under any T: maps cheaper than them are bought for it alone.
        let k0_maps = select(&k0, SCREEN, &p, &with_maps(m.clone(), 0.05), f64::INFINITY, None, true);
        assert_eq!((shadows(&k0_maps), k0_maps.shadow_maps), (vec![1, 1, 0], true));
        // Twelve shadow casters (0.1 ms each) and 1.05 ms left: ten traced, two left out. Neither the
        // maps (1.1 ms) nor every shadow (1.2 ms) fit: the ten stay, T kept.
        let many: Vec<ObjectStats> = (1..=12).map(|d| obj(100, d as f32, false)).collect();
        let over = select(&many, SCREEN, &p, &with_maps(model(&[0; 12]), 1.1), 5.05, None, true);
        assert_eq!((shadows(&over), over.shadow_maps), ([vec![1; 10], vec![0; 2]].concat(), false));
        assert!(over.predicted_ms <= 5.05 + 1e-9, "{}", over.predicted_ms);
        // Nothing left out: no maps, whatever they cost.
        let all = select(&objects, SCREEN, &p, &with_maps(m, 0.01), f64::INFINITY, None, true);
        assert_eq!((shadows(&all), all.shadow_maps), (vec![1, 1, 1], false));
    }

    #[test]
    fn unmeasured_objects_use_the_papers_estimate() {
        let m = model(&[2]);
        let o = obj(100, 1.0, true);
        assert_eq!(m.rays_per_pixel(0, 1, 99.0), 2.0);
        // Object 5 was never traced: Q for reflections is lights + 1.
        assert_eq!(m.rays_per_pixel(5, 1, estimated_rays(&o, 1, 1)[1]), 2.0);
        assert_eq!(estimated_rays(&ObjectStats { refractive: true, ..o }, 2, 3), [2.0, 4.0, 7.0]);
    }
}
