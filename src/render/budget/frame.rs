//! The budget's host side in a frame. Before the frame: reset the
//! statistics the `heuristic` pass gathers and write the selection the ray
//! passes honour. After it: turn the statistics into the next frame's
//! selection. One frame of latency, so neither side ever waits for the
//! other inside a frame; a renderer without a selection for the current
//! settings (the first frame, or the budget changed) measures one frame
//! first (see `Renderer::render`).

use anyhow::Result;

use super::paper::{self, ObjectStats, Params, Screen, Selection};
use super::BudgetSettings;
use crate::gpu::shared::{BUDGET_STAT_WORDS, MIRROR_ROUGHNESS};
use crate::gpu::GpuScene;
use crate::scene::{Aabb, Camera, Scene};

const WORDS: usize = BUDGET_STAT_WORDS as usize;

/// What the last selection saw and chose.
#[derive(Clone, Debug, PartialEq)]
pub struct BudgetReport {
    pub settings: BudgetSettings,
    /// Per object: what the frame measured.
    pub objects: Vec<ObjectStats>,
    pub selection: Selection,
}

impl BudgetReport {
    /// One line: how much was selected of what was visible.
    pub fn summary(&self) -> String {
        let visible = self.objects.iter().filter(|o| o.pixels > 0).count();
        format!(
            "budget {}: {} of {visible} visible objects ray-traced, estimated cost {:.0}",
            self.settings.budget,
            self.selection.selected.len(),
            self.selection.spent
        )
    }
}

#[derive(Default)]
pub struct BudgetState {
    /// The selection the next frame honours, and the settings it was made
    /// under.
    mask: Option<(BudgetSettings, Vec<bool>)>,
    last: Option<BudgetReport>,
}

impl BudgetState {
    /// Whether a selection exists for `settings` (else the next frame only
    /// measures).
    pub fn ready(&self, settings: &BudgetSettings) -> bool {
        self.mask_for(settings).is_some()
    }

    /// The selection made under `settings`, if the last one was.
    fn mask_for(&self, settings: &BudgetSettings) -> Option<&[bool]> {
        self.mask.as_ref().filter(|(s, _)| s == settings).map(|(_, m)| m.as_slice())
    }

    /// The last selection made, with what it was made from.
    pub fn last(&self) -> Option<&BudgetReport> {
        self.last.as_ref()
    }

    /// Resets the statistics and writes the selection for `objects`
    /// objects: the current one, or every object before the first.
    pub fn before_frame(&self, gpu: &mut GpuScene, settings: &BudgetSettings, objects: usize) -> Result<()> {
        let mut words = vec![0u32; objects.max(1) * WORDS];
        for w in words.chunks_exact_mut(WORDS) {
            // Count and maxima 0, minima at the largest value: atomicMin/Max.
            (w[1], w[2]) = (u32::MAX, u32::MAX);
        }
        gpu.budget_stats.write(0, bytemuck::cast_slice(&words))?;
        let mask: Vec<u32> = match self.mask_for(settings) {
            Some(m) => (0..objects.max(1)).map(|o| m.get(o).copied().unwrap_or(false) as u32).collect(),
            None => vec![1; objects.max(1)],
        };
        gpu.budget_mask.write(0, bytemuck::cast_slice(&mask))
    }

    /// Reads the statistics of the frame that just completed (rendered
    /// from `camera` at `screen`) and selects what the next frame traces.
    pub fn after_frame(
        &mut self,
        gpu: &GpuScene,
        scene: &Scene,
        camera: &Camera,
        screen: Screen,
        settings: &BudgetSettings,
    ) -> Result<()> {
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(gpu.budget_stats.read()?);
        let objects = object_stats(scene, camera, &words, self.mask_for(settings));
        let lights = scene.lights.len() as u32;
        let shadow_lights = scene.lights.iter().filter(|l| l.casts_shadows).count() as u32;
        let params =
            Params { budget: settings.budget, stickiness: settings.stickiness, shadow_lights, lights };
        let selection = paper::select(&paper::score(&objects, screen, &params), settings.budget);
        let mut mask = selection.mask.clone();
        mask.resize(scene.objects.len(), false);
        self.mask = Some((*settings, mask));
        let report = BudgetReport { settings: *settings, objects, selection };
        log::debug!("{}", report.summary());
        self.last = Some(report);
        Ok(())
    }
}

/// The paper's per-object inputs: A and the covered-pixel bounds from the
/// `heuristic` pass (`words`), D from the camera to the centre of the
/// object's world bounds, reflective / refractive from its materials (a
/// surface at most MIRROR_ROUGHNESS rough spawns reflection rays, a
/// transmissive one refraction rays), E and K from the object's properties,
/// S from `previous`.
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
        reflective[o] |= m.roughness <= MIRROR_ROUGHNESS;
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
