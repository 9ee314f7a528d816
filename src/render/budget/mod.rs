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
//! This is the host side of paper mode (`--budget-mode paper`): exactly
//! those formulas and that selection, `T` in the paper's abstract cost
//! units (rays, scaled by `E`). Where the paper leaves a detail open (the
//! falloff of `P`, ties, degenerate inputs) [`paper`] documents the choice.

//!
//! In a frame: the `heuristic` pass (render/passes/heuristic.rs) measures
//! `A` and the covered pixels' bounds of every object from the G-buffer's
//! hit ids; [`frame`] reads them after the frame and selects on the host
//! (one frame of latency: the selection is a few hundred objects of
//! arithmetic, and the host reads the statistics anyway, so no GPU sort);
//! the next frame's `direct`, `specular` and `composite` passes honour the
//! selection per pixel: an unselected object's pixels get no shadow,
//! reflection or refraction ray — exactly the raster-only shading (the
//! paper's fallback).

pub mod frame;
pub mod paper;

pub use frame::{BudgetReport, BudgetState};
pub use paper::{
    centrality, rays_per_pixel, score, select, ObjectStats, Params, Scored, Screen, Selection, MIN_DISTANCE,
};

/// How `--budget` selects.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum BudgetMode {
    /// Walewski et al.'s formulas and greedy selection, `--budget` in their
    /// abstract cost units (estimated rays x `cost`).
    #[default]
    Paper,
}

/// The per-object ray-tracing budget of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BudgetSettings {
    pub mode: BudgetMode,
    /// `T` (>= 0; infinite: every visible, relevant object).
    pub budget: f64,
    /// `I`, in the units of `V` (pixels per world unit).
    pub stickiness: f32,
}

impl BudgetSettings {
    /// Paper mode with budget `T` and no stickiness.
    pub fn paper(budget: f64) -> BudgetSettings {
        BudgetSettings { mode: BudgetMode::Paper, budget, stickiness: 0.0 }
    }
}
