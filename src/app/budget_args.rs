//! The command-line options of the per-object ray-tracing budget
//! (render/budget), shared by render, bench, report and view.

use clap::Args;

use crate::render::budget::{BudgetMode, BudgetSettings, Fallback};

/// The per-object ray-tracing budget (render/budget).
#[derive(Args, Clone)]
pub struct BudgetArgs {
    /// Ray-tracing budget T per frame: only the most relevant visible
    /// objects (effects mode: object and effect) whose cost fits get
    /// shadows, reflections and refractions, the others raster shading
    /// (effects mode: T in GPU ms of the ray stages; paper mode: in
    /// estimated rays x object cost; "inf": every visible object)
    /// [default: no budget].
    #[arg(long, value_parser = parse_budget, allow_hyphen_values = true, conflicts_with = "budget_ms")]
    pub budget: Option<f64>,
    /// The same as --budget T --budget-mode effects: T ms per frame for the
    /// ray stages (direct + specular).
    #[arg(long, value_parser = parse_budget, allow_hyphen_values = true)]
    pub budget_ms: Option<f64>,
    /// How --budget selects [default: effects].
    #[arg(long, value_enum, conflicts_with = "budget_ms")]
    pub budget_mode: Option<BudgetMode>,
    /// Stickiness I with --budget: relevance bonus of an object selected
    /// the frame before, in the units of the visibility A·P/D (pixels per
    /// world unit) [default: 0].
    #[arg(long, value_parser = parse_stickiness, allow_hyphen_values = true)]
    pub stickiness: Option<f32>,
    /// What an effect the budget leaves out shows instead: raster (the
    /// environment in the mirror / refracted direction; shadow maps for
    /// directional and spot lights, point lights unshadowed) or none (no
    /// shadow, reflection or refraction) [default: raster].
    #[arg(long, value_enum)]
    pub fallback: Option<Fallback>,
}

impl BudgetArgs {
    pub fn settings(&self) -> Option<BudgetSettings> {
        let (mode, budget) = match (self.budget, self.budget_ms) {
            (Some(t), _) => (self.budget_mode.unwrap_or_default(), t),
            (None, Some(ms)) => (BudgetMode::Effects, ms),
            (None, None) => return None,
        };
        Some(BudgetSettings {
            mode,
            budget,
            stickiness: self.stickiness.unwrap_or(0.0),
            fallback: self.fallback.unwrap_or_default(),
        })
    }

    /// Budget options given without a budget (they would change nothing).
    pub fn without_budget(&self) -> Option<&'static str> {
        let extra = self.budget_mode.is_some() || self.stickiness.is_some() || self.fallback.is_some();
        (self.settings().is_none() && extra).then_some(
            "--budget-mode, --stickiness and --fallback have no effect without --budget or --budget-ms",
        )
    }
}

fn parse_budget(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v >= 0.0 => Ok(v),
        _ => Err(format!("'{s}': expected a number >= 0, or inf")),
    }
}

fn parse_stickiness(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("'{s}': expected a finite number >= 0")),
    }
}
