//! A per-object ray-tracing budget: every frame, choose which visible
//! objects get ray-traced effects (shadows, reflections, refractions) so
//! that the estimated cost stays within a budget `T`, the others being
//! rasterized only. The heuristic is Walewski et al. (2019), on the hybrid
//! pipeline of Sabino and Andrade.
//!
//! Per visible object, each frame:
//! - `A`: its visible pixels;
//! - `P`: centrality, in [0.01, 1]: 1 with the projected bounding box's
//!   centre at the screen centre, 0.01 with it off screen;
//! - `D`: its distance from the camera;
//! - `V = A·P/D`: visibility (large, central, near objects matter most);
//! - `Q`: estimated rays per pixel: the shadow-casting lights, plus
//!   `lights + 1` when reflective, plus `lights + 4` when refractive;
//! - `C = A·Q·E`: cost, `E` a per-object cost factor set by the designer;
//! - `R = (S·I + V)·K`: relevance, `S` 1 when the object was selected
//!   last frame (else 0), `I` a global stickiness against flicker, `K` a
//!   per-object relevance factor (`K = 0`: never ray traced).
//!
//! Selection is greedy: while budget remains, among the objects whose cost
//! fits what is left take the most relevant and subtract its cost.
//!
//! [`paper`] is the host side of paper mode (`--budget-mode paper`): exactly
//! those formulas and that selection, `T` in the paper's abstract cost
//! units (rays, scaled by `E`). Where the paper leaves a detail open (the
//! falloff of `P`, ties, degenerate inputs) [`paper`] documents the choice.
//! [`effects`] is our mode, the default: the same relevance, selection per
//! (object, effect), costs in measured milliseconds.

//!
//! In a frame: the `heuristic` pass (render/passes/heuristic.rs) measures
//! `A` and the covered pixels' bounds of every object from the G-buffer's
//! hit ids; [`frame`] reads them after the frame and selects on the host
//! (one frame of latency: the selection is a few hundred objects of
//! arithmetic, and the host reads the statistics anyway, so no GPU sort);
//! the next frame's `direct`, `specular` and `composite` passes honour the
//! selection per pixel and effect (EFFECT_* bits; paper mode selects all
//! or none): an effect left out traces no ray. What it shows instead is the
//! [`Fallback`]: the paper's (no shadow, reflection or refraction at all)
//! or a raster approximation. The passes also count the rays each object
//! traced per effect, which effects mode's cost model reads.

pub mod effects;
pub mod frame;
pub mod paper;

pub use frame::{BudgetReport, BudgetState};
pub use paper::{
    centrality, rays_per_pixel, score, select, ObjectStats, Params, Scored, Screen, Selection, MIN_DISTANCE,
};

/// How `--budget` selects.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum BudgetMode {
    /// Per (object, effect), `--budget` in GPU ms of the ray stages
    /// (`direct` + `specular`), costs measured every frame ([`effects`]).
    #[default]
    Effects,
    /// Walewski et al.'s formulas and greedy selection, `--budget` in their
    /// abstract cost units (estimated rays x `cost`).
    Paper,
}

/// What an effect the budget leaves out shows instead (no ray is traced
/// either way).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Fallback {
    /// Reflections and refractions at the primary hit: the environment in
    /// the mirror / refracted direction, weighted like the traced branch;
    /// shadows of directional and spot lights: a shadow map (pass
    /// `shadow_map`). Point lights are unshadowed.
    #[default]
    Raster,
    /// The paper's fallback: raster-only shading, no shadow, reflection or
    /// refraction at all.
    None,
}

/// The per-object ray-tracing budget of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BudgetSettings {
    pub mode: BudgetMode,
    /// `T` (>= 0; infinite: every visible, relevant object): ms in effects
    /// mode, the paper's cost units in paper mode.
    pub budget: f64,
    /// `I`, in the units of `V` (pixels per world unit).
    pub stickiness: f32,
    /// What the effects left out show instead.
    pub fallback: Fallback,
}

impl BudgetSettings {
    /// Paper mode with budget `T`, no stickiness, the raster fallback.
    pub fn paper(budget: f64) -> BudgetSettings {
        BudgetSettings { mode: BudgetMode::Paper, budget, stickiness: 0.0, fallback: Fallback::Raster }
    }

    /// Effects mode with `ms` for the ray stages, no stickiness, the raster
    /// fallback.
    pub fn effects(ms: f64) -> BudgetSettings {
        BudgetSettings { mode: BudgetMode::Effects, budget: ms, stickiness: 0.0, fallback: Fallback::Raster }
    }
}
