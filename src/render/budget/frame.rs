//! The budget's host side: before a frame, reset the `heuristic` statistics and write the selection;
//! after it, turn the statistics into the next selection. One frame of latency, so neither side waits
//! inside a frame; without a selection for the current settings (first frame, budget changed) a
//! renderer measures one frame first (`Renderer::render`).

use anyhow::Result;

use super::effects::SHADOW_MAP_PASS;
use super::paper::{self, ObjectStats, Params, Screen, Selection};
use super::{effects, BudgetMode, BudgetSettings};
use crate::gpu::shared::{
    BUDGET_STAT_RAYS, BUDGET_STAT_WORDS, EFFECT_ALL, EFFECT_BIT_SHADOWS, GLOSSY_ROUGHNESS,
};
use crate::gpu::GpuScene;
use crate::scene::{Aabb, Camera, Scene};
use crate::vk::frame_ring::Uploads;

const WORDS: usize = BUDGET_STAT_WORDS as usize;

/// What the last selection saw and chose.
#[derive(Clone, Debug, PartialEq)]
pub struct BudgetReport {
    pub settings: BudgetSettings,
    pub objects: Vec<ObjectStats>,
    /// Objects selected for any effect (`spent`: paper cost units, or effects mode's predicted ms).
    pub selection: Selection,
    /// Per object, the EFFECT_* bits selected.
    pub effects: Vec<u32>,
    /// Effects mode: predicted and measured ms of the ray stages (`direct` + `specular`).
    pub predicted_ms: Option<f64>,
    pub measured_ms: f64,
    /// Effects mode: predicted and traced rays per ray stage (`direct`, `specular`), to tell a wrong ray
    /// estimate from a wrong ms per ray.
    pub predicted_rays: Option<[f64; 2]>,
    pub measured_rays: [f64; 2],
    /// The next frame may render the raster fallback's shadow maps (where it leaves shadows out).
    pub shadow_maps: bool,
    /// What the measured frame itself traced (the previous selection): selection words per object,
    /// and whether it rendered the shadow maps.
    pub traced: Vec<u32>,
    pub traced_maps: bool,
}

/// "N of M visible objects (n shadows, n reflections, n refractions[; a share of ...][; shadow maps])"
/// for selection words.
fn describe(words: &[u32], objects: &[ObjectStats], maps: bool) -> String {
    let visible = objects.iter().filter(|o| o.pixels > 0).count();
    let picked = words.iter().filter(|&&w| w != 0).count();
    let per_effect: Vec<String> = (0..effects::EFFECTS)
        .map(|e| {
            let n = words.iter().filter(|w| (**w >> e) & 1 == 1).count();
            format!("{n} {}", effects::EFFECT_NAMES[e])
        })
        .collect();
    let mut s = format!("{picked} of {visible} visible objects ({}", per_effect.join(", "));
    for (o, &w) in words.iter().enumerate() {
        for e in 0..effects::EFFECTS {
            let share = effects::traced_fraction(w, e);
            if share > 0.0 && share < 1.0 {
                s += &format!(
                    "; {} of object {o} on {:.1} % of its pixels",
                    effects::EFFECT_NAMES[e],
                    100.0 * share
                );
            }
        }
    }
    if maps {
        s += "; shadow maps";
    }
    s + ")"
}

impl BudgetReport {
    /// One line: what the measured frame traced and what the next one will.
    pub fn summary(&self) -> String {
        let picked = self.selection.selected.len();
        let visible = self.objects.iter().filter(|o| o.pixels > 0).count();
        match self.predicted_ms {
            Some(p) => {
                // NaN: the frame measured nothing (its first, or a debug view).
                let last = match self.measured_ms {
                    m if m.is_nan() => "ray stages not measured".to_string(),
                    m => format!("ray stages {m:.2} ms"),
                };
                format!(
                    "budget {} ms: this frame traced {}, {last}; next selection {}, predicted {p:.2} ms",
                    self.settings.budget,
                    describe(&self.traced, &self.objects, self.traced_maps),
                    describe(&self.effects, &self.objects, self.shadow_maps),
                )
            }
            None => format!(
                "budget {}: {picked} of {visible} visible objects ray-traced, estimated cost {:.0}",
                self.settings.budget, self.selection.spent
            ),
        }
    }
}

#[derive(Default)]
pub struct BudgetState {
    /// The selection for the next frame: the settings it was made under, EFFECT_* bits per object, and
    /// whether the frame may render the raster fallback's shadow maps (effects mode leaves them out where
    /// they cost more than the shadows they replace or do not fit the budget).
    mask: Option<(BudgetSettings, Vec<u32>, bool)>,
    /// The bits the frame in flight traces, per object, and whether it may render shadow maps.
    in_flight: Vec<u32>,
    in_flight_maps: bool,
    /// The frame's configuration has the `shadow_map` pass (`--fallback raster`, a light with a map).
    shadow_fallback: bool,
    /// Effects mode's measured costs (kept when the budget changes).
    model: effects::CostModel,
    last: Option<BudgetReport>,
}

impl BudgetState {
    /// Whether a selection exists for `settings` (else the next frame only measures).
    pub fn ready(&self, settings: &BudgetSettings) -> bool {
        self.mask_for(settings).is_some()
    }

    /// The selection made under `settings` (bits, shadow maps), if the last one was.
    fn next_for(&self, settings: &BudgetSettings) -> Option<(&[u32], bool)> {
        self.mask.as_ref().filter(|(s, ..)| s == settings).map(|(_, m, maps)| (m.as_slice(), *maps))
    }

    fn mask_for(&self, settings: &BudgetSettings) -> Option<&[u32]> {
        self.next_for(settings).map(|(m, _)| m)
    }

    /// The last selection made, with what it was made from.
    pub fn last(&self) -> Option<&BudgetReport> {
        self.last.as_ref()
    }

    /// Overrides the heuristic's selection for the next frame under `settings` (EFFECT_* bits per
    /// object): to check the passes honour any selection, and to replay one.
    pub fn set_selection(&mut self, settings: &BudgetSettings, bits: Vec<u32>) {
        self.mask = Some((*settings, bits, true));
    }

    /// Whether the frame in flight renders the raster fallback's shadow maps: its selection allows them
    /// and leaves out the shadows of an object with pixels (visible in the last statistics, or any object
    /// before there are any).
    pub fn shadow_maps_render(&self) -> bool {
        let visible =
            |o: usize| self.last.as_ref().is_none_or(|r| r.objects.get(o).is_none_or(|s| s.pixels > 0));
        self.in_flight_maps
            && self
                .in_flight
                .iter()
                .enumerate()
                .any(|(o, bits)| (bits >> EFFECT_BIT_SHADOWS) & 1 == 0 && visible(o))
    }

    /// Effects mode's cost model.
    pub fn model(&self) -> &effects::CostModel {
        &self.model
    }

    /// Resets the statistics and writes the selection for `objects` objects through the frame's ring
    /// slot: the current one, or everything before there is one (a measuring frame; effects mode
    /// calibrates with nothing, which also measures the shadow maps). Returns it for this frame's
    /// `after_frame`, since with frames in flight later frames select before this one completes.
    /// `shadow_fallback`: the configuration has the raster fallback's shadow maps.
    pub fn before_frame(
        &mut self,
        up: &mut Uploads,
        gpu: &GpuScene,
        settings: &BudgetSettings,
        objects: usize,
        shadow_fallback: bool,
    ) -> Result<Vec<u32>> {
        self.shadow_fallback = shadow_fallback;
        let mut words = vec![0u32; objects.max(1) * WORDS];
        for w in words.chunks_exact_mut(WORDS) {
            // Minima start at the largest value for atomicMin; the rest at 0.
            (w[1], w[2]) = (u32::MAX, u32::MAX);
        }
        up.write(&gpu.budget_stats, 0, bytemuck::cast_slice(&words))?;
        let measuring = match settings.mode {
            BudgetMode::Effects if !self.model.calibrated() => self.model.calibration_mask(),
            _ => EFFECT_ALL,
        };
        (self.in_flight, self.in_flight_maps) = match self.next_for(settings) {
            Some((m, maps)) => ((0..objects.max(1)).map(|o| m.get(o).copied().unwrap_or(0)).collect(), maps),
            None => (vec![measuring; objects.max(1)], true),
        };
        up.write(&gpu.budget_mask, 0, bytemuck::cast_slice(&self.in_flight))?;
        Ok(self.in_flight.clone())
    }

    /// Selects what the next frame traces from a completed frame's read-back statistics `words`.
    /// `timings`: its passes' GPU ms, None when not representative. With frames in flight the selection
    /// is one frame older than the frame it applies to.
    #[allow(clippy::too_many_arguments)]
    pub fn after_frame(
        &mut self,
        words: &[u32],
        traced: &[u32],
        scene: &Scene,
        camera: &Camera,
        screen: Screen,
        settings: &BudgetSettings,
        timings: Option<&[(&'static str, f64)]>,
    ) -> Result<()> {
        let n = scene.objects.len();
        let stage_ms = timings.map(|t| {
            effects::STAGES.map(|s| t.iter().filter(|(p, _)| s.contains(p)).map(|(_, ms)| ms).sum::<f64>())
        });
        let shadow_maps_ms =
            timings.and_then(|t| t.iter().find(|(p, _)| *p == SHADOW_MAP_PASS).map(|(_, ms)| *ms));
        let measured_ms =
            stage_ms.map_or(f64::NAN, |m| m.iter().sum::<f64>() + shadow_maps_ms.unwrap_or(0.0));
        let stat = |o: usize| words.get(o * WORDS..(o + 1) * WORDS).unwrap_or(&[0; WORDS]);
        let pixels: Vec<u32> = (0..n).map(|o| stat(o)[0]).collect();
        let rays: Vec<[u32; effects::EFFECTS]> =
            (0..n).map(|o| std::array::from_fn(|e| stat(o)[BUDGET_STAT_RAYS as usize + e])).collect();
        self.model.observe(&effects::Observation {
            pixels: &pixels,
            rays: &rays,
            traced,
            stage_ms,
            shadow_maps_ms,
        });
        let previous = self.mask_for(settings).map(|m| m.to_vec());
        let traced_before: Option<Vec<bool>> = previous.as_ref().map(|m| m.iter().map(|&b| b != 0).collect());
        let objects = object_stats(scene, camera, words, traced_before.as_deref());
        let lights = scene.lights.len() as u32;
        let shadow_lights = scene.lights.iter().filter(|l| l.casts_shadows).count() as u32;
        let params =
            Params { budget: settings.budget, stickiness: settings.stickiness, shadow_lights, lights };
        let mut measured_rays = [0.0; 2];
        for r in &rays {
            for (e, &n) in r.iter().enumerate() {
                measured_rays[effects::stage_of(e)] += n as f64;
            }
        }
        let (bits, predicted_ms, predicted_rays, selection, maps) = match settings.mode {
            BudgetMode::Paper => {
                let selection = paper::select(&paper::score(&objects, screen, &params), settings.budget);
                let mut bits: Vec<u32> =
                    selection.mask.iter().map(|&m| if m { EFFECT_ALL } else { 0 }).collect();
                bits.resize(n, 0);
                // Paper mode's T is in abstract units, which a pass's ms cannot join.
                (bits, None, None, selection, true)
            }
            BudgetMode::Effects => {
                if !self.model.calibrated() {
                    // Another calibration frame first; no selection yet.
                    return Ok(());
                }
                let chosen = effects::select(
                    &objects,
                    screen,
                    &params,
                    &self.model,
                    settings.budget,
                    previous.as_deref(),
                    self.shadow_fallback,
                );
                let selected: Vec<usize> = (0..n).filter(|&o| chosen.bits[o] != 0).collect();
                let spent = chosen.predicted_ms - chosen.base_ms;
                let mask = chosen.bits.iter().map(|&b| b != 0).collect();
                let predicted = (Some(chosen.predicted_ms), Some(chosen.predicted_rays));
                (
                    chosen.bits,
                    predicted.0,
                    predicted.1,
                    Selection { selected, spent, mask },
                    chosen.shadow_maps,
                )
            }
        };
        self.mask = Some((*settings, bits.clone(), maps));
        let report = BudgetReport {
            settings: *settings,
            objects,
            selection,
            effects: bits,
            predicted_ms,
            measured_ms,
            predicted_rays,
            measured_rays,
            shadow_maps: self.shadow_fallback && maps,
            traced: traced.to_vec(),
            // The timings list the pass when it rendered; without them, what the frame was given.
            traced_maps: shadow_maps_ms.is_some() || timings.is_none() && self.in_flight_maps,
        };
        log::debug!("{}", report.summary());
        self.last = Some(report);
        Ok(())
    }
}

/// The paper's per-object inputs: A and pixel bounds from `heuristic` (`words`), D to the centre of
/// the world bounds, reflective (roughness <= GLOSSY_ROUGHNESS: mirror or glossy, or such a coat) / refractive (transmissive) from the
/// materials, E and K from the object's properties, S from `previous`.
pub fn object_stats(
    scene: &Scene,
    camera: &Camera,
    words: &[u32],
    previous: Option<&[bool]>,
) -> Vec<ObjectStats> {
    let n = scene.objects.len();
    let mut bounds = vec![Aabb::EMPTY; n];
    let (mut reflective, mut refractive) = (vec![false; n], vec![false; n]);
    for inst in &scene.instances {
        let Some(o) = (inst.object < n).then_some(inst.object) else { continue };
        let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
        bounds[o] = bounds[o].union(&prim.bounds.transformed_f64(&inst.world));
        let m = &scene.materials[scene.instance_material(inst)];
        reflective[o] |= m.roughness_range().0 <= GLOSSY_ROUGHNESS
            || m.coat_roughness_range().is_some_and(|r| r.0 <= GLOSSY_ROUGHNESS);
        refractive[o] |= m.transmission > 0.0 && m.metallic < 1.0;
    }
    let eye = camera.position_f64();
    (0..n)
        .map(|o| {
            let w = words.get(o * WORDS..(o + 1) * WORDS).unwrap_or(&[0; WORDS]);
            let pixels = w[0];
            let (bbox_min, bbox_max) = if pixels > 0 {
                // Pixel indices to pixel-edge coordinates.
                ([w[1] as f32, w[2] as f32], [w[3] as f32 + 1.0, w[4] as f32 + 1.0])
            } else {
                ([0.0; 2], [0.0; 2])
            };
            let centre = (bounds[o].min.as_dvec3() + bounds[o].max.as_dvec3()) * 0.5;
            let distance = if bounds[o].is_empty() { f32::INFINITY } else { centre.distance(eye) as f32 };
            let props = &scene.objects[o].props;
            ObjectStats {
                pixels,
                bbox_min,
                bbox_max,
                distance,
                reflective: reflective[o],
                refractive: refractive[o],
                cost_factor: props.cost,
                relevance: props.relevance,
                selected_last_frame: previous.and_then(|m| m.get(o)).copied().unwrap_or(false),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_says_what_the_frame_traced_and_what_comes_next() {
        let seen = |pixels| ObjectStats {
            pixels,
            bbox_min: [0.0; 2],
            bbox_max: [1.0; 2],
            distance: 1.0,
            reflective: true,
            refractive: false,
            cost_factor: 1.0,
            relevance: 1.0,
            selected_last_frame: false,
        };
        let objects = vec![seen(100), seen(50), seen(0)];
        let quarter = effects::selection_word(0b001, 0b010, 0.25);
        let report = BudgetReport {
            settings: BudgetSettings::effects(20.0),
            objects,
            selection: Selection { selected: vec![0], spent: 3.0, mask: vec![true, false, false] },
            effects: vec![0b011, 0, 0],
            predicted_ms: Some(19.5),
            measured_ms: 21.25,
            predicted_rays: None,
            measured_rays: [0.0; 2],
            shadow_maps: true,
            traced: vec![0b001, quarter, 0],
            traced_maps: false,
        };
        assert_eq!(
            report.summary(),
            "budget 20 ms: this frame traced 2 of 2 visible objects (2 shadows, 0 reflections, 0 refractions; \
             reflections of object 1 on 25.0 % of its pixels), ray stages 21.25 ms; next selection 1 of 2 \
             visible objects (1 shadows, 1 reflections, 0 refractions; shadow maps), predicted 19.50 ms"
        );
        let unmeasured = BudgetReport { measured_ms: f64::NAN, traced_maps: true, ..report };
        assert!(unmeasured.summary().contains("of its pixels; shadow maps), ray stages not measured;"));
    }
}
