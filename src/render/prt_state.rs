//! The renderer's diffuse-PRT state: which transfer is on the GPU, and the
//! environment's radiance coefficients at its band count. The transfer is
//! computed (or loaded from the cache) when a frame first asks for a prt
//! ambient mode with an environment map; without one nothing is computed
//! and the scene set keeps its placeholder.

use anyhow::{Context as _, Result};

use super::RenderSettings;
use crate::gpu::scene::GpuScene;
use crate::prt::{default_cache_dir, PrtCache, PrtSettings};
use crate::scene::sh::{project_quadrature, Projection, ShCoeffs};
use crate::scene::Scene;
use crate::vk::Context;

#[derive(Default)]
pub struct PrtState {
    /// What the GPU buffer holds (None: the placeholder).
    uploaded: Option<PrtSettings>,
    /// The map's radiance coefficients at `uploaded`'s bands.
    radiance: Option<ShCoeffs>,
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
        if want == self.uploaded {
            return Ok(());
        }
        let Some(s) = want else {
            gpu.set_prt(ctx, None)?;
            (self.uploaded, self.radiance) = (None, None);
            return Ok(());
        };
        let cache = PrtCache::new(default_cache_dir());
        let (transfer, _) = cache.get(scene, &s).context("PRT precompute")?;
        gpu.set_prt(ctx, Some(&crate::gpu::prt_buffer::pack(&transfer)))?;
        let map = scene.environment.map.as_ref().context("PRT without an environment map")?;
        // The scene's 3-band projection is reused; other band counts project
        // the map again (same quadrature and Hann window).
        self.radiance = Some(match &gpu.env_sh {
            Some(sh) if sh.bands() == s.bands => sh.clone(),
            _ => project_quadrature(map, &Projection { bands: s.bands, ..Default::default() })?,
        });
        self.uploaded = Some(s);
        Ok(())
    }

    /// The radiance coefficients while a transfer is on the GPU.
    pub fn radiance(&self) -> Option<&ShCoeffs> {
        self.radiance.as_ref()
    }
}
