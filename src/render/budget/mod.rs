//! A per-object ray-tracing budget: each frame, choose which visible objects get ray-traced effects
//! (shadows, reflections, refractions) so the estimated cost stays within `T`; the rest are
//! rasterized only. The heuristic is Walewski et al. (2019), on Sabino and Andrade's hybrid pipeline.
//!
//! Per visible object, each frame:
//! - `A`: its visible pixels;
//! - `P`: centrality in [0.01, 1]: 1 with the projected box's centre at the screen centre, 0.01 off
//!   screen;
//! - `D`: its distance from the camera;
//! - `V = A·P/D`: visibility;
//! - `Q`: estimated rays per pixel: shadow-casting lights, plus `lights + 1` when reflective, plus
//!   `lights + 4` when refractive;
//! - `C = A·Q·E`: cost, `E` a designer-set per-object factor;
//! - `R = (S·I + V)·K`: relevance, `S` 1 if selected last frame, `I` a global stickiness against
//!   flicker, `K` a per-object factor (`K = 0`: never ray traced).
//!
//! Selection is greedy: while budget remains, take the most relevant object whose cost fits.
//!
//! [`paper`] is paper mode (`--budget-mode paper`): exactly those formulas, `T` in the paper's
//! abstract cost units, with the choices the paper leaves open documented there. [`effects`], the
//! default, selects per (object, effect) with costs in measured milliseconds.
//!
//! The `heuristic` pass (render/passes/heuristic.rs) measures `A` and pixel bounds from the hit ids;
//! [`frame`] selects on the host after the frame (one frame of latency, but no GPU sort for a few
//! hundred objects whose statistics the host reads anyway); the next frame's `direct`, `specular` and
//! `composite` honour it per pixel and effect (EFFECT_* bits). A left-out effect traces no ray and
//! shows the [`Fallback`] instead. The passes also count rays per object and effect for effects
//! mode's cost model.

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
    /// Per (object, effect), `--budget` in GPU ms of the ray stages (`direct` + `specular`), costs
    /// measured every frame ([`effects`]).
    #[default]
    Effects,
    /// Walewski et al.'s formulas and greedy selection, `--budget` in their abstract cost units
    /// (estimated rays x `cost`).
    Paper,
}

/// What an effect the budget leaves out shows instead (no ray is traced either way).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Fallback {
    /// The environment in the mirror / refracted direction, weighted like the traced branch; shadows of
    /// directional and spot lights from a shadow map (`shadow_map` pass). Point lights are unshadowed.
    #[default]
    Raster,
    /// The paper's: raster-only shading, no shadow, reflection or refraction at all.
    None,
}

/// The per-object ray-tracing budget of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BudgetSettings {
    pub mode: BudgetMode,
    /// `T` (>= 0; infinite: every visible, relevant object): ms in effects mode, cost units in paper mode.
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

    /// Effects mode with `ms` for the ray stages, no stickiness, the raster fallback.
    pub fn effects(ms: f64) -> BudgetSettings {
        BudgetSettings { mode: BudgetMode::Effects, budget: ms, stickiness: 0.0, fallback: Fallback::Raster }
    }
}
