//! Effects mode (`--budget-mode effects`, `--budget-ms T`): the paper's
//! relevance, but selection per (object, effect) — an object may get
//! reflections and no shadows — and costs in milliseconds of the ray
//! stages, so `T` is a real time budget for `direct` + `specular`.
//!
//! The cost model, per ray stage (shadows are traced in `direct`,
//! reflection and refraction chains in `specular`):
//! `stage ms = base + k · rays`, where `base` is the stage's time with
//! nothing traced (it shades every pixel anyway) and `k` its time per
//! ray. Both are measured, not assumed: `base` in a calibration frame with
//! the selection empty, `k` from every frame that traced something, as a
//! ratio of exponential moving averages (`EMA(ms − base) / EMA(rays)`,
//! so frames with few rays, whose ratio is mostly noise, weigh little).
//! The rays an (object, effect) needs per covered pixel come from the
//! frames that traced it (the passes count them per object and effect,
//! `BUDGET_STAT_RAYS`); an object not yet traced is estimated with the
//! paper's `Q` terms for that effect.
//!
//! The selection is the paper's greedy rule on (object, effect) pairs:
//! cost `A · rays per pixel · k`, relevance `(S·I + V)·K` with `S` for
//! that pair, within `T − base(direct) − base(specular)`. The model
//! corrects itself: if `k` is off, the next frame's rays show it, and the
//! iteration `rays → T/(ms per ray)` has the budget as its fixed point as
//! long as the stages' base fits in it. `E` (the designer's cost factor)
//! is not used: the cost is measured.

use super::paper::{self, ObjectStats, Scored, Screen};
use crate::gpu::shared::{EFFECT_BIT_REFLECTIONS, EFFECT_BIT_REFRACTIONS, EFFECT_BIT_SHADOWS, EFFECT_COUNT};

pub const EFFECTS: usize = EFFECT_COUNT as usize;

/// The effects' names, by `EFFECT_BIT_*`.
pub const EFFECT_NAMES: [&str; EFFECTS] = ["shadows", "reflections", "refractions"];

/// The ray stages, the pass that traces each, and each effect's stage.
pub const STAGES: [&str; 2] = ["direct", "specular"];
const fn stage_of(effect: usize) -> usize {
    if effect == EFFECT_BIT_SHADOWS as usize {
        0
    } else {
        1
    }
}

/// Weight of a new frame in the moving averages.
const SMOOTHING: f64 = 0.3;

/// One ray stage's `ms = base + k · rays`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageFit {
    /// The stage with nothing traced (None until a frame traced nothing).
    pub base_ms: Option<f64>,
    /// EMA of `ms − base` and of the rays, over frames that traced rays.
    excess_ms: f64,
    rays: f64,
}

impl StageFit {
    /// ms per ray (0 before any frame traced a ray in this stage).
    pub fn ms_per_ray(&self) -> f64 {
        if self.rays > 0.0 {
            self.excess_ms / self.rays
        } else {
            0.0
        }
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
        if self.rays > 0.0 {
            self.excess_ms += SMOOTHING * (excess - self.excess_ms);
            self.rays += SMOOTHING * (rays - self.rays);
        } else {
            (self.excess_ms, self.rays) = (excess, rays);
        }
    }

    /// Predicted stage ms for `rays`.
    pub fn predict(&self, rays: f64) -> f64 {
        self.base_ms.unwrap_or(0.0) + self.ms_per_ray() * rays
    }
}

/// What one finished frame showed the model.
pub struct Observation<'a> {
    /// Per object: the statistics words' pixels and rays per effect.
    pub pixels: &'a [u32],
    pub rays: &'a [[u32; EFFECTS]],
    /// The effect bits each object traced in that frame.
    pub traced: &'a [u32],
    /// GPU ms of the `direct` and `specular` passes (0 when left out;
    /// None when the frame's times are not representative, e.g. a shader
    /// compiled on first use inside them).
    pub stage_ms: Option<[f64; 2]>,
}

/// The measured cost model, kept across frames (and budgets).
#[derive(Clone, Debug, Default)]
pub struct CostModel {
    pub stages: [StageFit; 2],
    /// Per object and effect: rays per covered pixel when last traced.
    rays_per_pixel: Vec<[Option<f64>; EFFECTS]>,
    /// A frame that traced every effect of every object has been seen.
    seen_full: bool,
}

impl CostModel {
    /// Both calibration frames seen: the empty one (bases) and the full
    /// one (rays per pixel of everything visible, and `k`).
    pub fn calibrated(&self) -> bool {
        self.seen_full && self.stages.iter().all(|s| s.base_ms.is_some())
    }

    /// The selection the next calibration frame needs: nothing traced for
    /// the stages' bases, then everything.
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
                if (traced >> e) & 1 == 0 {
                    all_traced &= pixels == 0;
                } else if pixels > 0 {
                    self.rays_per_pixel[i][e] = Some(rays[e] as f64 / pixels as f64);
                }
            }
        }
        let Some(stage_ms) = o.stage_ms else { return };
        for (s, fit) in self.stages.iter_mut().enumerate() {
            // A stage that traced no ray shows its base.
            fit.observe(stage_ms[s], stage_rays[s]);
        }
        self.seen_full |= all_traced && o.pixels.iter().any(|&p| p > 0);
    }

    /// Rays per covered pixel of `object`'s `effect`: measured, else the
    /// paper's estimate for that effect.
    pub fn rays_per_pixel(&self, object: usize, effect: usize, estimate: f64) -> f64 {
        self.rays_per_pixel.get(object).and_then(|r| r[effect]).unwrap_or(estimate)
    }
}

/// The paper's `Q`, split by effect: shadow-casting lights for shadows,
/// `lights + 1` for a reflective object's reflections, `lights + 4` for a
/// refractive one's refractions; 0 for an effect the object cannot have.
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
    /// Per object, the EFFECT_* bits traced.
    pub bits: Vec<u32>,
    /// Predicted ms of the ray stages with this selection (bases included).
    pub predicted_ms: f64,
    /// The bases alone (what any selection costs).
    pub base_ms: f64,
}

/// Selects (object, effect) pairs within `budget_ms` for the ray stages.
/// `previous`: the bits selected last frame (stickiness per pair).
pub fn select(
    objects: &[ObjectStats],
    screen: Screen,
    params: &paper::Params,
    model: &CostModel,
    budget_ms: f64,
    previous: Option<&[u32]>,
) -> EffectsSelection {
    // The paper's score gives V and K per object; cost and S are per pair.
    let scored = paper::score(objects, screen, params);
    let stickiness = if params.stickiness.is_finite() { params.stickiness as f64 } else { 0.0 };
    let k = [0usize, 1].map(|s| model.stages[s].ms_per_ray());
    let mut pairs = Vec::new();
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
            pairs.push(Scored {
                object: o * EFFECTS + e,
                pixels: s.pixels,
                visibility: s.visibility,
                cost: s.pixels as f64 * rays * k[stage_of(e)],
                relevance,
            });
        }
    }
    let base_ms: f64 = model.stages.iter().map(|s| s.base_ms.unwrap_or(0.0)).sum();
    let chosen = paper::select(&pairs, budget_ms - base_ms);
    let mut bits = vec![0u32; objects.len()];
    for id in &chosen.selected {
        bits[id / EFFECTS] |= 1 << (id % EFFECTS);
    }
    EffectsSelection { bits, predicted_ms: base_ms + chosen.spent, base_ms }
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
        });
        assert!(!m.calibrated() && m.calibration_mask() == crate::gpu::shared::EFFECT_ALL);
        let rays: Vec<[u32; EFFECTS]> = refl.iter().map(|&r| [100, 100 * r, 0]).collect();
        let all = vec![crate::gpu::shared::EFFECT_ALL; objects];
        let refl_rays: u32 = refl.iter().sum::<u32>() * 100;
        let ms = [2.0 + 0.001 * 100.0 * objects as f64, 2.0 + 0.01 * refl_rays as f64];
        m.observe(&Observation { pixels: &pixels, rays: &rays, traced: &all, stage_ms: None });
        assert!(!m.calibrated(), "a frame without representative times calibrates nothing");
        m.observe(&Observation { pixels: &pixels, rays: &rays, traced: &all, stage_ms: Some(ms) });
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
    fn selection_is_per_effect_and_fits_the_budget() {
        // Costs: shadows 0.1 ms, reflections 2 ms per object (of 100 px).
        let objects = [obj(100, 1.0, true), obj(100, 2.0, true), obj(100, 4.0, false)];
        let m = model(&[2, 2, 0]);
        // Bases 4 ms; 2.35 ms left, in order of relevance: the nearest
        // object's shadows and reflections (2.1 ms), the second's shadows,
        // not its reflections (2 ms more), the third's shadows.
        let s = select(&objects, SCREEN, &params(0.0), &m, 6.35, None);
        assert_eq!(s.bits, vec![0b011, 0b001, 0b001]);
        assert!((s.predicted_ms - (4.0 + 2.0 + 0.3)).abs() < 1e-9, "{}", s.predicted_ms);
        // Below the bases nothing; an unlimited budget everything possible.
        assert_eq!(select(&objects, SCREEN, &params(0.0), &m, 3.9, None).bits, vec![0; 3]);
        let all = select(&objects, SCREEN, &params(0.0), &m, f64::INFINITY, None);
        assert_eq!(all.bits, vec![0b011, 0b011, 0b001]);
    }

    #[test]
    fn stickiness_is_per_pair_and_k_zero_is_never_selected() {
        let mut objects = [obj(100, 1.0, true), obj(100, 1.0, true)];
        let m = model(&[2, 2]);
        // Equal objects, room for one reflection: without stickiness the
        // lower id; with it, the pair selected last frame.
        let p = params(1e3);
        assert_eq!(select(&objects, SCREEN, &p, &m, 6.25, None).bits, vec![0b011, 0b001]);
        assert_eq!(select(&objects, SCREEN, &p, &m, 6.25, Some(&[0b001, 0b011])).bits, vec![0b001, 0b011]);
        objects[0].relevance = 0.0;
        assert_eq!(select(&objects, SCREEN, &p, &m, f64::INFINITY, None).bits, vec![0, 0b011]);
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
