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

pub mod paper;

pub use paper::{
    centrality, rays_per_pixel, score, select, ObjectStats, Params, Scored, Screen, Selection, MIN_DISTANCE,
};
