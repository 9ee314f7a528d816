//! The command-line options of the environment light (image-based lighting),
//! shared by render, bench, report and view: a map replacing the scene's,
//! its layout, rotation and intensity, and how the ambient term uses it.

use std::path::PathBuf;

use anyhow::{Context as _, Result};
use clap::Args;

use crate::render::{AmbientMode, ReferenceSettings};
use crate::scene::{scene_file::load_env_map, EnvLayout, Scene};

/// The environment overrides (the scene file's [environment] otherwise).
#[derive(Args, Clone, Debug, Default)]
pub struct EnvArgs {
    /// Radiance .hdr environment map replacing (or adding) the scene's.
    #[arg(long, value_name = "PATH")]
    pub env: Option<PathBuf>,
    /// With --env: how the image maps directions (angular: Debevec's
    /// square light probe, converted to equirect on load) [default: equirect].
    #[arg(long, value_enum, requires = "env")]
    pub env_layout: Option<EnvLayout>,
    /// Rotation of the environment about +Y in degrees (finite), replacing
    /// the scene's `rotation_deg`.
    #[arg(long, value_name = "DEG", value_parser = parse_rotation, allow_hyphen_values = true)]
    pub env_rotation: Option<f32>,
    /// Environment radiance multiplier (finite, >= 0), replacing the scene's
    /// `intensity`.
    #[arg(long, value_name = "X", value_parser = parse_intensity, allow_hyphen_values = true)]
    pub env_intensity: Option<f32>,
    /// Diffuse environment light: traced (sh shadowed by ray-traced visibility
    /// at the primary hit, denoised), sh (the map's irradiance, per normal,
    /// from its spherical-harmonic projection, unshadowed), constant (the
    /// map's mean radiance for every normal), or precomputed radiance
    /// transfer on the static geometry: prt-unshadowed, prt-shadowed,
    /// prt-interreflected (cached on disk; animated and skinned objects get
    /// sh) [default: traced].
    #[arg(long, value_enum)]
    pub ambient: Option<AmbientMode>,
    /// With --ambient traced: the ambient rays bring only the environment's
    /// light, not the direct and environment light of the surfaces they hit
    /// (the one indirect bounce); emissive surfaces still light the scene.
    #[arg(long)]
    pub no_indirect: bool,
    /// PRT directions per vertex: N gives N×N stratified jittered samples
    /// over the sphere (1..=1024) [default: 16].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=crate::prt::MAX_SAMPLES as i64))]
    pub prt_samples: Option<u32>,
    /// Interreflection bounces of prt-interreflected (0..=16) [default: 1].
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(0..=crate::prt::MAX_BOUNCES as i64))]
    pub prt_bounces: Option<u32>,
    /// SH bands of the PRT transfer and environment (1..=8, bands² coefficients) [default: 3].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=crate::scene::sh::MAX_BANDS as i64))]
    pub prt_bands: Option<u32>,
    /// Ray-traced reference for the diffuse environment light: N
    /// cosine-weighted visibility samples per pixel at the primary hit,
    /// accumulated over frames (render renders ceil(N/4) frames), replacing
    /// the ambient term there.
    #[arg(long, value_name = "N", value_parser = parse_samples, allow_hyphen_values = true)]
    pub reference_samples: Option<u32>,
    /// With --reference-samples: rays per path; 1 = environment light with
    /// visibility, K > 1 adds K - 1 diffuse bounces [default: 1].
    #[arg(
        long,
        value_name = "K",
        value_parser = parse_bounces,
        requires = "reference_samples",
        allow_hyphen_values = true
    )]
    pub reference_bounces: Option<u32>,
}

/// What [`EnvArgs`] changes in a loaded scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EnvOverrides {
    pub map: Option<(PathBuf, EnvLayout)>,
    /// Degrees.
    pub rotation_deg: Option<f32>,
    pub intensity: Option<f32>,
}

impl EnvArgs {
    pub fn prt_options(&self) -> crate::render::PrtOptions {
        let d = crate::render::PrtOptions::default();
        crate::render::PrtOptions {
            samples: self.prt_samples.unwrap_or(d.samples),
            bounces: self.prt_bounces.unwrap_or(d.bounces),
            bands: self.prt_bands.map_or(d.bands, |b| b as usize),
            ..d
        }
    }

    /// The ray-traced reference the flags ask for.
    pub fn reference(&self) -> Option<ReferenceSettings> {
        self.reference_samples
            .map(|samples| ReferenceSettings { samples, bounces: self.reference_bounces.unwrap_or(1) })
    }

    pub fn overrides(&self) -> EnvOverrides {
        EnvOverrides {
            map: self.env.clone().map(|p| (p, self.env_layout.unwrap_or_default())),
            rotation_deg: self.env_rotation,
            intensity: self.env_intensity,
        }
    }
}

impl EnvOverrides {
    /// Applies the overrides to `scene`; errors name the flag.
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        if let Some((path, layout)) = &self.map {
            let map = load_env_map(path, *layout).with_context(|| format!("--env {}", path.display()))?;
            scene.environment.map = Some(map);
            scene.environment.map_path = Some(path.clone());
        }
        if let Some(deg) = self.rotation_deg {
            scene.environment.rotation = deg.to_radians();
        }
        if let Some(i) = self.intensity {
            scene.environment.intensity = i;
        }
        Ok(())
    }
}

fn parse_rotation(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{s}': expected a finite angle in degrees")),
    }
}

fn parse_intensity(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("'{s}': expected a finite number >= 0")),
    }
}

/// Most samples per pixel the reference accepts (2^20: days on lavapipe).
const MAX_REFERENCE_SAMPLES: u32 = 1 << 20;
/// Most rays per reference path.
const MAX_REFERENCE_BOUNCES: u32 = 16;

fn parse_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (1..=MAX_REFERENCE_SAMPLES).contains(&v) => Ok(v),
        _ => {
            Err(format!("'{s}': expected a whole number of samples per pixel, 1 to {MAX_REFERENCE_SAMPLES}"))
        }
    }
}

fn parse_bounces(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (1..=MAX_REFERENCE_BOUNCES).contains(&v) => Ok(v),
        _ => Err(format!(
            "'{s}': expected 1 to {MAX_REFERENCE_BOUNCES} rays per path (1: visibility only, K: K - 1 bounces)"
        )),
    }
}
