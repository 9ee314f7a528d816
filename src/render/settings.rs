//! What a frame is asked for: the settings every command and the viewer
//! pass to `Renderer::render`.

use super::budget;
use super::shading::{AaMode, Backend, Effects, Mode};
use super::tone::ToneSettings;

/// How the ambient term lights surfaces from an environment map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum AmbientMode {
    /// The map's irradiance at the surface normal, from its 3-band SH
    /// projection (gpu/env_sh.rs).
    #[default]
    Sh,
    /// The map's mean radiance for every normal (the behaviour before SH).
    Constant,
}

/// G-buffer debug views (also selectable in the viewer).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum DebugView {
    #[default]
    None,
    Albedo,
    Normal,
    Depth,
    Material,
    Object,
    /// The ray-tracing budget's selection (`--budget`): traced objects red.
    Selection,
}

impl DebugView {
    pub(super) fn code(self) -> u32 {
        use crate::gpu::shared::*;
        match self {
            DebugView::None => DEBUG_NONE,
            DebugView::Albedo => DEBUG_ALBEDO,
            DebugView::Normal => DEBUG_NORMAL,
            DebugView::Depth => DEBUG_DEPTH,
            DebugView::Material => DEBUG_MATERIAL,
            DebugView::Object => DEBUG_OBJECT,
            DebugView::Selection => DEBUG_SELECTION,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// The exposure with auto exposure off; with it on, a compensation
    /// factor on the measured one.
    pub exposure: f32,
    pub tone: ToneSettings,
    pub debug_view: DebugView,
    pub mode: Mode,
    pub effects: Effects,
    pub backend: Backend,
    /// Anti-aliasing after tone mapping (edge by default).
    pub aa: AaMode,
    /// Per-object ray-tracing budget (None: every object is traced).
    pub budget: Option<budget::BudgetSettings>,
    /// Diffuse environment light with a map (without one it is the
    /// constant colour either way).
    pub ambient: AmbientMode,
    /// The ray-traced reference replaces the ambient radiance at primary
    /// hits (--reference-samples; render/reference.rs).
    pub reference: Option<super::ReferenceSettings>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            exposure: 1.0,
            tone: ToneSettings::default(),
            debug_view: DebugView::None,
            mode: Mode::Hybrid,
            effects: Effects::default(),
            backend: Backend::Auto,
            aa: AaMode::Edge,
            budget: None,
            ambient: AmbientMode::Sh,
            reference: None,
        }
    }
}
