//! The options every rendering command shares (`render`, `bench`,
//! `report`, `view`): scene, camera, mode, effects, tone mapping,
//! animation, budget and environment, turned into a [`RenderJob`].

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use glam::Vec3;

use super::cli_parse::*;
use super::{BudgetArgs, CameraChoice, EnvArgs, PathArgs, RenderJob};
use crate::render::settings::PrimaryVisibility;
use crate::render::shading::{AaMode, Backend, Effects, Mode};
use crate::render::tone::{AutoExposure, ToneOperator, ToneSettings};
use crate::render::{DebugView, RenderSettings};

#[derive(Args, Clone)]
pub struct ViewArgs {
    /// glTF/GLB, OBJ or TOML scene file (default: assets/default.toml, in
    /// the working directory, next to the executable or in the source tree).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Image width in pixels (1..=16384).
    #[arg(long, default_value_t = 1280, value_parser = parse_resolution, allow_hyphen_values = true)]
    pub width: u32,
    /// Image height in pixels (1..=16384).
    #[arg(long, default_value_t = 720, value_parser = parse_resolution, allow_hyphen_values = true)]
    pub height: u32,
    /// Index of the scene camera to use.
    #[arg(long, conflicts_with = "look_from")]
    pub camera: Option<usize>,
    /// Camera position "x,y,z" (finite; with --look-at).
    #[arg(long, value_parser = super::parse_vec3, requires = "look_at", allow_hyphen_values = true)]
    pub look_from: Option<Vec3>,
    /// Camera target "x,y,z" (finite; with --look-from).
    #[arg(long, value_parser = super::parse_vec3, requires = "look_from", allow_hyphen_values = true)]
    pub look_at: Option<Vec3>,
    /// Vertical field of view in degrees, in (0, 180), for --look-from/--look-at [default: 60].
    #[arg(long, value_parser = parse_fov, allow_hyphen_values = true)]
    pub fov: Option<f32>,
    /// Exposure multiplier before tone mapping (finite, > 0); with
    /// --auto-exposure, a compensation on the measured exposure. With
    /// neither, the scene file's `[environment] exposure` applies, and a
    /// scene without one is auto-exposed (histogram) [default: 1].
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    pub exposure: Option<f32>,
    #[command(flatten)]
    pub tone: ToneArgs,
    /// Show a G-buffer target instead of the lit image.
    #[arg(long, value_enum, default_value_t = DebugView::None)]
    pub debug_view: DebugView,
    /// hybrid: G-buffer primary hits + traced secondary rays; rt: trace camera
    /// rays too; path: the path-traced ground truth (--samples).
    #[arg(long, value_enum, default_value_t = Mode::Hybrid)]
    pub mode: Mode,
    #[command(flatten)]
    pub path: PathArgs,
    /// Ray traversal backend.
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    pub backend: Backend,
    /// Hybrid mode's primary hits: raster (visibility buffer), traced
    /// (camera rays) or auto (view and bench: measure both per view, keep
    /// the cheaper; render: a size model, raster but traced for dense frames of
    /// large scenes on a software device, so images do not depend on timing).
    #[arg(long, value_enum, default_value_t = PrimaryVisibility::Auto)]
    pub primary_visibility: PrimaryVisibility,
    /// Two-phase occlusion culling of the raster G-buffer's clusters (the
    /// image is the same; off by default: the shipped camera paths hide
    /// almost nothing, see README).
    #[arg(long, value_enum, default_value_t = OnOff::Off)]
    pub occlusion_culling: OnOff,
    /// Anti-aliasing after tone mapping: edge (G-buffer depth and normal
    /// discontinuities), fxaa (luminance edges) or none [default: edge].
    #[arg(long, value_enum)]
    pub aa: Option<AaMode>,
    /// Trace no shadow rays: punctual lights reach every surface unoccluded.
    #[arg(long)]
    pub no_shadows: bool,
    /// Trace no reflections: mirrors (roughness up to 0.1) and glossy
    /// surfaces (up to 0.6) then reflect the prefiltered environment alone.
    #[arg(long)]
    pub no_reflections: bool,
    /// Trace no refractions: transmissive surfaces show only their
    /// reflection and ambient terms.
    #[arg(long)]
    pub no_refractions: bool,
    /// Maximum reflection/refraction recursion depth (0..=64).
    #[arg(long, default_value_t = 8, value_parser = parse_max_depth, allow_hyphen_values = true)]
    pub max_depth: u32,
    /// Importance cutoff in [0, 1]: branches with a smaller weight are not traced.
    #[arg(long, default_value_t = 0.01, value_parser = parse_min_weight, allow_hyphen_values = true)]
    pub min_weight: f32,
    /// glTF animation to play, by name or index.
    #[arg(long)]
    pub animation: Option<String>,
    /// Animation time in seconds, finite, with --animation (render: the
    /// frame's time; bench and view: the start) [default: 0].
    #[arg(long, value_parser = parse_time, allow_hyphen_values = true)]
    pub time: Option<f32>,
    /// Fixed animation step (finite, > 0), with --animation: frame i is at
    /// time + i / fps (bench: 30 when not given; view: wall-clock playback
    /// when not given).
    #[arg(long, value_parser = parse_fps, allow_hyphen_values = true)]
    pub fps: Option<f32>,
    #[command(flatten)]
    pub budget: BudgetArgs,
    #[command(flatten)]
    pub env: EnvArgs,
}

/// Tone mapping and auto exposure (render/tone.rs).
#[derive(Args, Clone)]
pub struct ToneArgs {
    /// Tone curve.
    #[arg(long, value_enum, default_value_t = ToneOperator::Reinhard)]
    pub tonemap: ToneOperator,
    /// Exposure from the frame's luminance: off (fixed --exposure),
    /// log-average (Reinhard's key / log-average), histogram (percentile-clipped
    /// log-luminance histogram). Still frames converge at once; bench and
    /// view adapt over time [default: off with --exposure; else the scene
    /// file's `exposure`, histogram where it has none].
    #[arg(long, value_enum)]
    pub auto_exposure: Option<AutoExposure>,
    /// Key: the exposed luminance the frame's average maps to (finite, > 0),
    /// with --auto-exposure [default: 0.18].
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    pub key: Option<f32>,
    /// White point of --tonemap reinhard-white in exposed luminance (finite,
    /// > 0) [default: the frame's brightest pixel].
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    pub white_point: Option<f32>,
    /// Histogram auto exposure: the darkest and brightest fractions of
    /// pixels left out, "LOW,HIGH" with 0 <= LOW < HIGH <= 1 [default: 0.1,0.9].
    #[arg(long, value_parser = parse_percentiles, allow_hyphen_values = true)]
    pub histogram_clip: Option<(f32, f32)>,
    /// Histogram auto exposure: adaptation speeds in EV per second,
    /// "BRIGHTEN,DARKEN" (finite, > 0) [default: 3,1].
    #[arg(long, value_parser = parse_speeds, allow_hyphen_values = true)]
    pub adapt_speed: Option<(f32, f32)>,
}

impl ToneArgs {
    pub fn settings(&self) -> ToneSettings {
        let d = ToneSettings::default();
        let (histogram_low, histogram_high) =
            self.histogram_clip.unwrap_or((d.histogram_low, d.histogram_high));
        let (speed_brighten, speed_darken) = self.adapt_speed.unwrap_or((d.speed_brighten, d.speed_darken));
        ToneSettings {
            operator: self.tonemap,
            auto_exposure: self.auto_exposure.unwrap_or(AutoExposure::Off),
            key: self.key.unwrap_or(d.key),
            white: self.white_point,
            histogram_low,
            histogram_high,
            speed_brighten,
            speed_darken,
        }
    }

    /// A tone option the chosen operator or exposure mode does not read.
    pub fn without_effect(&self) -> Option<&'static str> {
        let histogram = self.auto_exposure == Some(AutoExposure::Histogram);
        if self.key.is_some() && self.auto_exposure == Some(AutoExposure::Off) {
            return Some("--key has no effect without --auto-exposure (the fixed --exposure applies)");
        }
        if self.white_point.is_some() && self.tonemap != ToneOperator::ReinhardWhite {
            return Some("--white-point has no effect without --tonemap reinhard-white");
        }
        if (self.histogram_clip.is_some() || self.adapt_speed.is_some())
            && self.auto_exposure.is_some()
            && !histogram
        {
            return Some(
                "--histogram-clip and --adapt-speed have no effect without --auto-exposure histogram",
            );
        }
        None
    }
}

impl ViewArgs {
    /// Options that would change nothing here: refused (a usage error), so a
    /// typo'd or misplaced option is not silently ignored.
    pub fn without_effect(&self, command: &str) -> Option<String> {
        if let Some(why) = self.tone.without_effect() {
            return Some(why.into());
        }
        if self.fov.is_some() && self.look_from.is_none() {
            return Some(
                "--fov has no effect without --look-from/--look-at (scene cameras keep their own)".into(),
            );
        }
        if let Some(why) = self.budget.without_budget() {
            return Some(why.into());
        }
        if self.env.reference_samples.is_some() && self.debug_view != DebugView::None {
            return Some(
                "--reference-samples has no effect with --debug-view (it shows the G-buffer)".into(),
            );
        }
        if let Some(why) = self.path.without_effect(self.mode) {
            return Some(why.into());
        }
        if self.path.samples.is_some() && (command == "view" || command == "bench") {
            return Some(format!(
                "--samples has no effect on {command}: it adds 4 paths per pixel a frame while the view stays still"
            ));
        }
        if self.mode == Mode::Path {
            if self.env.reference_samples.is_some() {
                return Some(
                    "--reference-samples has no effect with --mode path (it traces everything)".into(),
                );
            }
            if self.aa.is_some_and(|a| a != AaMode::None) {
                return Some(
                    "--aa has no effect with --mode path: its jittered camera paths integrate each pixel"
                        .into(),
                );
            }
        }
        if self.time.is_some() && self.animation.is_none() {
            return Some("--time has no effect without --animation".into());
        }
        if self.fps.is_some() && self.animation.is_none() {
            return Some("--fps has no effect without --animation".into());
        }
        if self.fps.is_some() && command == "render" {
            return Some(
                "--fps has no effect on render (one frame at --time; it steps bench and view)".into(),
            );
        }
        None
    }

    /// The render job these options describe.
    pub fn job(&self) -> Result<RenderJob> {
        let camera = match (self.camera, self.look_from, self.look_at) {
            (Some(i), _, _) => CameraChoice::Index(i),
            (None, Some(from), Some(to)) => {
                CameraChoice::LookAt { from, to, yfov_deg: self.fov.unwrap_or(60.0) }
            }
            _ => CameraChoice::First,
        };
        let scene = match &self.scene {
            Some(s) => s.clone(),
            None => super::default_scene_path()?,
        };
        Ok(RenderJob {
            scene,
            width: self.width,
            height: self.height,
            camera,
            settings: RenderSettings {
                exposure: self.exposure.unwrap_or(1.0),
                tone: self.tone.settings(),
                exposure_from_scene: self.exposure.is_none() && self.tone.auto_exposure.is_none(),
                debug_view: self.debug_view,
                mode: self.mode,
                backend: self.backend,
                aa: self.aa.unwrap_or_default(),
                effects: Effects {
                    shadows: !self.no_shadows,
                    reflections: !self.no_reflections,
                    refractions: !self.no_refractions,
                    max_depth: self.max_depth,
                    min_weight: self.min_weight,
                    count_rays: false,
                },
                budget: self.budget.settings(),
                ambient: self.env.ambient.unwrap_or_default(),
                ambient_from_scene: self.env.ambient.is_none(),
                ambient_bounce: !self.env.no_indirect,
                prt: self.env.prt_options(),
                reference: self.env.reference(),
                terms: 0,
                path: self.path.settings(),
                primary_visibility: self.primary_visibility,
                occlusion_culling: self.occlusion_culling == OnOff::On,
                ..RenderSettings::default()
            },
            animation: self.animation.clone(),
            time: self.time.unwrap_or(0.0),
            fps: self.fps.unwrap_or(30.0),
            supersample: None,
            env: self.env.overrides(),
        })
    }
}

/// A switch on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum OnOff {
    On,
    Off,
}
