//! What a frame is asked for: the settings every command and the viewer pass to `Renderer::render`.

use super::budget;
use super::tone::ToneSettings;
use crate::gpu::shared::REFERENCE_SAMPLES_PER_FRAME;
use crate::scene::SceneExposure;

/// How the ambient term lights surfaces from an environment map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum AmbientMode {
    /// `Sh` shadowed per pixel by ray-traced visibility, plus one indirect bounce (render/passes/ao.rs):
    /// the share of the environment's light that cosine rays from the primary hit find unoccluded and
    /// the light their hits send back, denoised. The default: without visibility an interior is lit by
    /// the sky seen through its walls. `Sh` with `--no-shadows` or `--budget` (AmbientMode::pick).
    #[default]
    Traced,
    /// The map's irradiance at the surface normal, from its 3-band SH
    /// projection (gpu/env_sh.rs), unshadowed.
    Sh,
    /// The map's mean radiance for every normal (the behaviour before SH).
    Constant,
    /// Diffuse PRT (src/prt) on static geometry at the primary hit:
    /// clamped cosine only; everything else gets `Sh`.
    PrtUnshadowed,
    /// PRT with visibility (ambient shadowing).
    PrtShadowed,
    /// PRT with visibility and interreflection (`--prt-bounces`).
    PrtInterreflected,
}

impl AmbientMode {
    /// `settings.ambient`, or the scene file's where it applies.
    pub fn resolve(settings: &RenderSettings, env: &crate::scene::Environment) -> AmbientMode {
        AmbientMode::pick(settings, AmbientMode::of_scene(env))
    }

    /// The scene file's `[environment] ambient`, if it names one.
    pub fn of_scene(env: &crate::scene::Environment) -> Option<AmbientMode> {
        use clap::ValueEnum;
        env.ambient.as_deref().and_then(|name| AmbientMode::from_str(name, false).ok())
    }

    /// `settings.ambient`, or `scene`'s (AmbientMode::of_scene) where the command line gave none. `Traced`
    /// shadows the sky with rays, so it is `Sh` where shadows are off (a raster-only frame traces nothing)
    /// and under a budget, whose cost model does not hold it yet.
    pub fn pick(settings: &RenderSettings, scene: Option<AmbientMode>) -> AmbientMode {
        let mode = match (scene, settings.ambient_from_scene) {
            (Some(mode), true) => mode,
            _ => settings.ambient,
        };
        match mode {
            AmbientMode::Traced if !settings.effects.shadows || settings.budget.is_some() => AmbientMode::Sh,
            m => m,
        }
    }

    /// The PRT transfer this mode shades with, if any.
    pub fn prt_mode(self) -> Option<crate::prt::PrtMode> {
        use crate::prt::PrtMode;
        match self {
            AmbientMode::Traced | AmbientMode::Sh | AmbientMode::Constant => None,
            AmbientMode::PrtUnshadowed => Some(PrtMode::Unshadowed),
            AmbientMode::PrtShadowed => Some(PrtMode::Shadowed),
            AmbientMode::PrtInterreflected => Some(PrtMode::Interreflected),
        }
    }
}

/// The PRT precompute's parameters (`--prt-samples`, `--prt-bounces`, `--prt-bands`); used only by the prt
/// ambient modes. `projection` is how the environment is projected onto SH for the sh and prt modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrtOptions {
    /// N: N×N directions a vertex.
    pub samples: u32,
    pub bounces: u32,
    pub bands: usize,
    pub projection: EnvProjection,
}

/// The integrator of the environment's SH projection (report knob `sh-samples`; scene/sh/project.rs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EnvProjection {
    /// Per-texel solid-angle quadrature (what the scene upload uses).
    #[default]
    Exact,
    /// Stratified jittered N×N Monte-Carlo, fixed seed.
    MonteCarlo(u32),
}

impl EnvProjection {
    /// The Monte-Carlo projection's seed, fixed so a report row is reproducible.
    pub const SEED: u64 = 0x5eed;

    pub fn integrator(self) -> crate::scene::sh::Integrator {
        use crate::scene::sh::Integrator;
        match self {
            EnvProjection::Exact => Integrator::Quadrature,
            EnvProjection::MonteCarlo(n) => Integrator::MonteCarlo { n, seed: Self::SEED },
        }
    }
}

impl Default for PrtOptions {
    fn default() -> Self {
        use crate::prt::{DEFAULT_BOUNCES, DEFAULT_SAMPLES};
        Self {
            samples: DEFAULT_SAMPLES,
            bounces: DEFAULT_BOUNCES,
            bands: crate::scene::sh::DEFAULT_BANDS,
            projection: EnvProjection::Exact,
        }
    }
}

/// How the hybrid frame finds its primary hits (the visibility buffer that
/// `gbuffer_resolve` reads): rasterized or traced, or chosen per view by
/// measured GPU cost (render/visibility.rs). Pure ray-traced mode always traces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PrimaryVisibility {
    /// Measure both (GPU timestamps of a probe frame each) and keep the
    /// cheaper, re-measuring when the view changes a lot or every few
    /// hundred frames. Only a renderer told to measure (the viewer and
    /// `bench` set `choices.visibility.measure`) does; elsewhere (`render`,
    /// tests, goldens: images must not depend on timing) auto follows a size
    /// model (`visibility::model`): raster, but traced for dense frames of
    /// large scenes on a software device with the compute tracer.
    #[default]
    Auto,
    /// The raster visibility buffer (pass `gbuffer`).
    Raster,
    /// Camera rays through the pixel centres (pass `visibility_trace`).
    Traced,
}

impl PrimaryVisibility {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            PrimaryVisibility::Auto => "auto",
            PrimaryVisibility::Raster => "raster",
            PrimaryVisibility::Traced => "traced",
        }
    }

    pub fn is_traced(self) -> bool {
        self == PrimaryVisibility::Traced
    }
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
    /// For tools (the report's per-object error): the linear radiance is
    /// the primary hit's object index + 1, 0 where nothing is hit.
    #[value(skip)]
    ObjectId,
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
            DebugView::ObjectId => DEBUG_OBJECT_ID,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// The exposure with auto exposure off; with it on, a compensation factor on the measured one.
    pub exposure: f32,
    pub tone: ToneSettings,
    /// Neither `--exposure` nor `--auto-exposure` was given: the scene file's `exposure` applies, and
    /// without one histogram auto exposure (`RenderSettings::exposure_for`).
    pub exposure_from_scene: bool,
    pub debug_view: DebugView,
    pub mode: Mode,
    pub effects: Effects,
    pub backend: Backend,
    /// Anti-aliasing after tone mapping (edge by default).
    pub aa: AaMode,
    /// Per-object ray-tracing budget (None: every object is traced).
    pub budget: Option<budget::BudgetSettings>,
    /// Diffuse environment light with a map (without one it is the constant colour either way).
    pub ambient: AmbientMode,
    /// `ambient` was not given on the command line: the scene file's
    /// `[environment] ambient` wins where it has one.
    pub ambient_from_scene: bool,
    /// `Traced`'s rays bring the emission and direct light of what they hit (one indirect bounce;
    /// `--no-indirect` turns it off). A frame flag: switching it compiles nothing.
    pub ambient_bounce: bool,
    pub prt: PrtOptions,
    /// The ray-traced reference replaces the ambient radiance at primary
    /// hits (--reference-samples; render/reference.rs).
    pub reference: Option<ReferenceSettings>,
    /// The report's attribution: these `TERM_*` terms come from the path tracer, accumulated over frames like
    /// the reference (pass `terms`; 0: none). Not with `reference` or a debug view. No flag.
    pub terms: u32,
    /// The path tracer's samples, path length and clamp (`--mode path` only).
    pub path: super::path::PathSettings,
    /// How hybrid mode finds primary hits (--primary-visibility).
    pub primary_visibility: PrimaryVisibility,
    /// Two-phase occlusion culling of the raster G-buffer's clusters (render/occlusion.rs;
    /// --occlusion-culling); the image is the same either way. Off by default: the shipped camera paths
    /// hide almost nothing (Sponza: 3 of 5,731 clusters) and the cost shows; wall-facing interiors cull
    /// ~40% of their clusters (bench/results/lavapipe-2core-vm-raster.md).
    pub occlusion_culling: bool,
    /// The edge filter shares its pixels' depths and triangle exits within 8x8 tiles (glsl/aa_edge.comp).
    /// False runs the per-pixel version: the same image, slower; the tiled one's reference in tests. No flag.
    pub edge_aa_tiled: bool,
    /// Glossy reflections draw new lobe samples each frame and reuse the reprojected history
    /// (render/passes/glossy_temporal.rs): on for frame sequences (the viewer). Off, each frame is the
    /// same one-sample frame whatever came before (`render`, `bench`, `report`, tests). No flag.
    pub glossy_temporal: bool,
}

impl RenderSettings {
    /// The exposure and tone settings a frame uses: these settings' own, or where the command line named
    /// neither `--exposure` nor `--auto-exposure`, the scene file's `exposure` (`scene`), and without one
    /// histogram auto exposure: a scene that authors no exposure (a glTF file, say) is neither black nor
    /// blown out at whatever its light units are.
    pub fn exposure_for(&self, scene: Option<SceneExposure>) -> (f32, ToneSettings) {
        use super::tone::AutoExposure;
        if !self.exposure_from_scene {
            return (self.exposure, self.tone);
        }
        match scene {
            Some(SceneExposure::Fixed(e)) => {
                (e, ToneSettings { auto_exposure: AutoExposure::Off, ..self.tone })
            }
            Some(SceneExposure::Auto) | None => {
                (1.0, ToneSettings { auto_exposure: AutoExposure::Histogram, ..self.tone })
            }
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            exposure: 1.0,
            tone: ToneSettings::default(),
            exposure_from_scene: false,
            debug_view: DebugView::None,
            mode: Mode::Hybrid,
            effects: Effects::default(),
            backend: Backend::Auto,
            aa: AaMode::Edge,
            budget: None,
            ambient: AmbientMode::Traced,
            ambient_from_scene: false,
            ambient_bounce: true,
            prt: PrtOptions::default(),
            reference: None,
            terms: 0,
            path: Default::default(),
            primary_visibility: PrimaryVisibility::Auto,
            occlusion_culling: false,
            edge_aa_tiled: true,
            glossy_temporal: false,
        }
    }
}

/// What the reference integrates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceSettings {
    /// Samples per pixel of the converged image (rounded up to whole frames).
    pub samples: u32,
    /// Rays per path: 1 = environment light with visibility, K > 1 adds K - 1 diffuse bounces.
    pub bounces: u32,
}

impl ReferenceSettings {
    /// Frames that reach `samples` at REFERENCE_SAMPLES_PER_FRAME a frame.
    pub fn frames(&self) -> u32 {
        self.samples.div_ceil(REFERENCE_SAMPLES_PER_FRAME).max(1)
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Mode {
    /// G-buffer primary hits + traced secondary rays.
    #[default]
    Hybrid,
    /// Camera rays traced too (reference for the hybrid image).
    Rt,
    /// The path-traced ground truth (`--samples` paths per pixel,
    /// render/path.rs): every light transport the scene has, no
    /// approximation but the sample count.
    Path,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// Ray query where supported, else the ray-tracing pipeline, else the
    /// compute BVH tracer.
    #[default]
    Auto,
    /// VK_KHR_ray_query.
    Query,
    /// VK_KHR_ray_tracing_pipeline (ray generation + hit shaders).
    Pipeline,
    /// Our own BVH traversed in a compute shader (no ray-tracing extension).
    Compute,
}

/// Anti-aliasing of the tone-mapped frame (render/passes/antialias.rs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum AaMode {
    /// The tone-mapped frame as it is.
    None,
    /// Geometric edge filter: depth and normal discontinuities of the
    /// G-buffer pick the pixels to blur (Shishkovtsov; Sabino Eq. 4.2).
    #[default]
    Edge,
    /// Luminance edge filter in the style of FXAA 3.11 (quality preset).
    Fxaa,
}

impl Backend {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Query => "query",
            Backend::Pipeline => "pipeline",
            Backend::Compute => "compute",
        }
    }
}

impl AaMode {
    pub const ALL: [AaMode; 3] = [AaMode::None, AaMode::Edge, AaMode::Fxaa];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AaMode::None => "none",
            AaMode::Edge => "edge",
            AaMode::Fxaa => "fxaa",
        }
    }
}

/// User-facing switches (all on by default; the scene may still not need them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Effects {
    pub shadows: bool,
    pub reflections: bool,
    pub refractions: bool,
    /// Maximum recursion depth of reflection/refraction branches.
    pub max_depth: u32,
    /// Branches whose weight falls below this are not traced.
    pub min_weight: f32,
    /// Count rays by kind (benchmarks; costs atomics).
    pub count_rays: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Self {
            shadows: true,
            reflections: true,
            refractions: true,
            max_depth: 8,
            min_weight: 0.01,
            count_rays: false,
        }
    }
}

impl Effects {
    pub const NONE: Effects = Effects {
        shadows: false,
        reflections: false,
        refractions: false,
        max_depth: 8,
        min_weight: 0.01,
        count_rays: false,
    };
}

#[cfg(test)]
mod tests {
    use clap::ValueEnum;

    use super::*;

    /// The command line's exposure wins; else the scene's; else histogram auto exposure.
    #[test]
    fn exposure_comes_from_the_command_line_then_the_scene_then_auto() {
        use crate::render::tone::AutoExposure;
        let log = ToneSettings { auto_exposure: AutoExposure::LogAverage, key: 0.3, ..Default::default() };
        let cli = RenderSettings { exposure: 2.0, tone: log, ..Default::default() };
        for scene in [None, Some(SceneExposure::Fixed(0.5)), Some(SceneExposure::Auto)] {
            assert_eq!(cli.exposure_for(scene), (2.0, log), "{scene:?}");
        }
        let unset = RenderSettings { exposure_from_scene: true, ..cli };
        let (e, t) = unset.exposure_for(Some(SceneExposure::Fixed(0.5)));
        assert_eq!((e, t.auto_exposure, t.key), (0.5, AutoExposure::Off, 0.3));
        for scene in [None, Some(SceneExposure::Auto)] {
            let (e, t) = unset.exposure_for(scene);
            assert_eq!((e, t.auto_exposure, t.key), (1.0, AutoExposure::Histogram, 0.3), "{scene:?}");
        }
    }

    /// The scene file accepts exactly the command line's names.
    #[test]
    fn ambient_names_match_the_scene_files() {
        let names: Vec<String> = AmbientMode::value_variants()
            .iter()
            .map(|v| v.to_possible_value().unwrap().get_name().to_string())
            .collect();
        assert_eq!(names, crate::scene::AMBIENT_NAMES);
        let env = crate::scene::Environment { ambient: Some("prt-shadowed".into()), ..Default::default() };
        let cli = RenderSettings { ambient: AmbientMode::Constant, ..Default::default() };
        assert_eq!(AmbientMode::resolve(&cli, &env), AmbientMode::Constant);
        let unset = RenderSettings { ambient_from_scene: true, ..cli };
        assert_eq!(AmbientMode::resolve(&unset, &env), AmbientMode::PrtShadowed);
    }
}
