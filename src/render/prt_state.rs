//! The renderer's diffuse-PRT state: which transfer is on the GPU, and the
//! environment's radiance coefficients at its band count. The transfer is
//! computed (or loaded from the cache) when a frame first asks for a prt
//! ambient mode with an environment map; without one nothing is computed
//! and the scene set keeps its placeholder. It also holds the map's
//! projection when a frame asks for another integrator than the scene
//! upload's exact quadrature (`PrtOptions::projection`, the report's
//! `sh-samples` knob).

use anyhow::{Context as _, Result};

use super::settings::EnvProjection;
use super::RenderSettings;
use crate::gpu::env_sh::SH_BANDS;
use crate::gpu::scene::GpuScene;
use crate::prt::{default_cache_dir, CacheOutcome, PrtCache, PrtSettings};
use crate::scene::sh::{project, Projection, ShCoeffs};
use crate::scene::{HdrImage, Scene};
use crate::vk::Context;

#[derive(Default)]
pub struct PrtState {
    /// What the GPU buffer holds (None: the placeholder).
    uploaded: Option<PrtSettings>,
    /// Whether that transfer came from the disk cache or was computed.
    outcome: Option<CacheOutcome>,
    /// The map's radiance coefficients at `uploaded`'s bands.
    radiance: Option<ShCoeffs>,
    /// The last projections other than the scene's exact 3-band one: a
    /// frame may ask for two (PRT's bands and the SH irradiance's 3), and
    /// one slot would project the map twice every frame.
    projected: Vec<(EnvProjection, usize, ShCoeffs)>,
}

impl PrtState {
    /// Makes the GPU hold the transfer `settings` asks for (or none).
    pub fn ensure(
        &mut self,
        ctx: &Context,
        gpu: &mut GpuScene,
        scene: &Scene,
        settings: &RenderSettings,
    ) -> Result<()> {
        let want = match (settings.ambient.prt_mode(), &scene.environment.map) {
            (Some(mode), Some(_)) => Some(PrtSettings {
                mode,
                bands: settings.prt.bands,
                samples: settings.prt.samples,
                bounces: settings.prt.bounces,
            }),
            _ => None,
        };
        if want != self.uploaded {
            self.outcome = match want {
                None => {
                    gpu.set_prt(ctx, None)?;
                    None
                }
                Some(s) => {
                    let cache = PrtCache::new(default_cache_dir());
                    let (transfer, outcome) = cache.get(scene, &s).context("PRT precompute")?;
                    gpu.set_prt(ctx, Some(&crate::prt::pack(&transfer)))?;
                    Some(outcome)
                }
            };
            self.uploaded = want;
        }
        self.radiance = match (want, &scene.environment.map) {
            (Some(s), Some(map)) => Some(self.projected(gpu, map, s.bands, settings.prt.projection)?),
            _ => None,
        };
        Ok(())
    }

    /// Where the transfer on the GPU came from (None: no transfer).
    pub fn outcome(&self) -> Option<CacheOutcome> {
        self.outcome
    }

    /// The radiance coefficients while a transfer is on the GPU.
    pub fn radiance(&self) -> Option<&ShCoeffs> {
        self.radiance.as_ref()
    }

    /// The 3-band radiance coefficients the SH irradiance is made of,
    /// projected the way `projection` says (None without a map).
    pub fn sh_radiance(
        &mut self,
        gpu: &GpuScene,
        scene: &Scene,
        projection: EnvProjection,
    ) -> Result<Option<ShCoeffs>> {
        match &scene.environment.map {
            Some(map) if gpu.env_sh.is_some() => Ok(Some(self.projected(gpu, map, SH_BANDS, projection)?)),
            _ => Ok(gpu.env_sh.clone()),
        }
    }

    /// The map's coefficients at `bands` by `projection`: the scene
    /// upload's exact 3-band projection is reused, the last other one is
    /// kept (same Hann window either way).
    fn projected(
        &mut self,
        gpu: &GpuScene,
        map: &HdrImage,
        bands: usize,
        projection: EnvProjection,
    ) -> Result<ShCoeffs> {
        if let (EnvProjection::Exact, SH_BANDS, Some(sh)) = (projection, bands, &gpu.env_sh) {
            return Ok(sh.clone());
        }
        if let Some((_, _, sh)) = self.projected.iter().find(|(p, b, _)| (*p, *b) == (projection, bands)) {
            return Ok(sh.clone());
        }
        let sh = project(map, &Projection { bands, ..Default::default() }, projection.integrator())
            .with_context(|| format!("projecting the environment onto {bands} SH bands ({projection:?})"))?;
        if self.projected.len() == 2 {
            self.projected.remove(0);
        }
        self.projected.push((projection, bands, sh.clone()));
        Ok(sh)
    }
}
