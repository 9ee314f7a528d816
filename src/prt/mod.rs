//! Diffuse precomputed radiance transfer (Sloan, Kautz & Snyder 2002) for static geometry, on the CPU;
//! a layer above `scene` and `accel` (visibility through the CPU BVH).
//!
//! Per vertex of every static instance a transfer vector T with irradiance E = sum_k T_k L_k, L_k the
//! environment's radiance coefficients (T holds the clamped cosine; albedo a exits a E / pi):
//! - unshadowed: T_k = ∫ max(0, n·w) y_k(w) dw (monochrome);
//! - shadowed: times the visibility V(w) (`transfer`);
//! - interreflected: plus k bounces, each adding for occluded directions the hit point's albedo / pi
//!   times its previous-bounce transfer (`interreflect`): RGB, since albedo is coloured.
//!
//! Integration: one set of N×N stratified jittered directions over the sphere (`--prt-samples N`;
//! half face away from any normal), shared by every vertex so the basis is evaluated once per
//! direction. Results are cached on disk (`cache`).

mod cache;
mod interreflect;
mod pack;
mod transfer;

use std::time::Instant;

use anyhow::{ensure, Result};
use glam::{DMat3, DVec3};

pub use cache::{default_cache_dir, key as cache_key, user_cache_dir, CacheOutcome, PrtCache, CACHE_DIR_ENV};
pub use pack::pack;
pub use transfer::offset_origin;

use crate::scene::sh::{check_bands, ShCoeffs};
use crate::scene::Scene;

pub use crate::scene::AMBIENT_NAMES;

/// Bump when the computation or the file layout changes: it is part of the
/// cache key.
pub const FORMAT_VERSION: u32 = 1;
/// Default `--prt-samples` (N, for N² directions).
pub const DEFAULT_SAMPLES: u32 = 16;
/// Default `--prt-bounces`.
pub const DEFAULT_BOUNCES: u32 = 1;
/// Largest N: 1024² ≈ 1e6 directions a vertex is already far past useful.
pub const MAX_SAMPLES: u32 = 1024;
/// Largest bounce count.
pub const MAX_BOUNCES: u32 = 16;
/// Seed of the jittered directions (fixed: the result is deterministic).
const SEED: u64 = 0x5052_5421;

/// Which transfer is precomputed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrtMode {
    Unshadowed,
    Shadowed,
    Interreflected,
}

impl PrtMode {
    /// Floats per coefficient: interreflected transfer is RGB.
    pub fn channels(self) -> usize {
        match self {
            PrtMode::Interreflected => 3,
            _ => 1,
        }
    }

    fn code(self) -> u32 {
        match self {
            PrtMode::Unshadowed => 0,
            PrtMode::Shadowed => 1,
            PrtMode::Interreflected => 2,
        }
    }
}

/// What is precomputed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrtSettings {
    pub mode: PrtMode,
    /// SH bands (bands² coefficients), 1..=8.
    pub bands: usize,
    /// N: N×N stratified directions over the sphere.
    pub samples: u32,
    /// Interreflection bounces (interreflected only).
    pub bounces: u32,
}

impl PrtSettings {
    pub fn new(mode: PrtMode) -> Self {
        Self { mode, bands: 3, samples: DEFAULT_SAMPLES, bounces: DEFAULT_BOUNCES }
    }

    pub fn check(&self) -> Result<()> {
        check_bands(self.bands)?;
        ensure!(
            (1..=MAX_SAMPLES).contains(&self.samples),
            "--prt-samples must be in 1..={MAX_SAMPLES} (got {})",
            self.samples
        );
        ensure!(
            self.bounces <= MAX_BOUNCES,
            "--prt-bounces must be in 0..={MAX_BOUNCES} (got {})",
            self.bounces
        );
        Ok(())
    }

    /// Bounces that actually run (0 unless interreflected).
    fn effective_bounces(&self) -> u32 {
        if self.mode == PrtMode::Interreflected {
            self.bounces
        } else {
            0
        }
    }
}

/// Per-vertex transfer of a scene's static instances.
#[derive(Clone, Debug, PartialEq)]
pub struct PrtTransfer {
    pub settings: PrtSettings,
    /// Per `Scene::instances` entry: the first vertex of its range in
    /// `data`, or `None` for an animated or skinned instance.
    pub first_vertex: Vec<Option<u32>>,
    /// Vertex-major: vertex v, coefficient k, channel c at
    /// `(v * bands² + k) * channels + c`.
    pub data: Vec<f32>,
    /// Visibility rays traced (0 for unshadowed or a cache load).
    pub rays: u64,
}

impl PrtTransfer {
    pub fn coeffs(&self) -> usize {
        self.settings.bands * self.settings.bands
    }

    pub fn channels(&self) -> usize {
        self.settings.mode.channels()
    }

    pub fn vertex_count(&self) -> usize {
        self.data.len() / (self.coeffs() * self.channels()).max(1)
    }

    /// Transfer of vertex `v`: bands² × channels floats.
    pub fn vertex(&self, v: usize) -> &[f32] {
        let n = self.coeffs() * self.channels();
        &self.data[v * n..][..n]
    }

    /// Irradiance E (rgb) at vertex `v` under the radiance coefficients
    /// `env` (which must have at least as many bands).
    pub fn irradiance(&self, v: usize, env: &ShCoeffs) -> [f64; 3] {
        let ch = self.channels();
        let mut e = [0.0; 3];
        for (k, l) in env.coeffs().iter().take(self.coeffs()).enumerate() {
            for (c, ec) in e.iter_mut().enumerate() {
                *ec += self.vertex(v)[k * ch + c.min(ch - 1)] as f64 * l[c];
            }
        }
        e
    }
}

/// Per node: whether an animation channel moves it or one of its ancestors.
pub fn animated_nodes(scene: &Scene) -> Vec<bool> {
    let mut direct = vec![false; scene.nodes.len()];
    for c in scene.animations.iter().flat_map(|a| &a.channels) {
        if let Some(d) = direct.get_mut(c.node) {
            *d = true;
        }
    }
    (0..scene.nodes.len())
        .map(|n| {
            // Bounded climb: a (rejected) cycle cannot hang it.
            let mut at = Some(n);
            for _ in 0..=scene.nodes.len() {
                match at {
                    Some(i) if direct[i] => return true,
                    Some(i) => at = scene.nodes[i].parent,
                    None => break,
                }
            }
            false
        })
        .collect()
}

/// Indices into `scene.instances` of the static ones.
pub fn static_instances(scene: &Scene) -> Vec<usize> {
    let animated = animated_nodes(scene);
    (0..scene.instances.len())
        .filter(|&i| {
            let inst = &scene.instances[i];
            inst.skinned.is_none() && !animated.get(inst.node).copied().unwrap_or(true)
        })
        .collect()
}

/// A static vertex in world space (f64 world matrix applied).
#[derive(Clone, Copy, Debug)]
pub(crate) struct WorldVertex {
    pub p: DVec3,
    pub n: DVec3,
    /// Largest world coordinate magnitude of its primitive (the offset's
    /// extent, as offset.glsl takes the triangle's).
    pub extent: f64,
}

/// World-space static vertices, in `first_vertex` order.
pub(crate) fn world_vertices(scene: &Scene, statics: &[usize]) -> (Vec<WorldVertex>, Vec<Option<u32>>) {
    let mut first = vec![None; scene.instances.len()];
    let mut out = Vec::new();
    for &i in statics {
        let inst = &scene.instances[i];
        let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
        first[i] = Some(out.len() as u32);
        let normal_m = DMat3::from_mat4(inst.world).inverse().transpose();
        let b = prim.bounds.transformed_f64(&inst.world);
        let extent = b.min.abs().max(b.max.abs()).max_element() as f64;
        for v in &prim.vertices {
            let p = inst.world.transform_point3(glam::Vec3::from(v.position).as_dvec3());
            let n = (normal_m * glam::Vec3::from(v.normal).as_dvec3()).normalize_or_zero();
            out.push(WorldVertex { p, n, extent });
        }
    }
    (out, first)
}

/// Computes the transfer of `scene`'s static instances (no cache).
pub fn compute(scene: &Scene, settings: &PrtSettings) -> Result<PrtTransfer> {
    settings.check()?;
    let t0 = Instant::now();
    let statics = static_instances(scene);
    let (verts, first_vertex) = world_vertices(scene, &statics);
    log::info!(
        "prt: computing {:?} transfer, {} bands, {}² directions{}, {} vertices of {} static instances",
        settings.mode,
        settings.bands,
        settings.samples,
        match settings.mode {
            PrtMode::Interreflected => format!(", {} bounce(s)", settings.bounces),
            _ => String::new(),
        },
        verts.len(),
        statics.len()
    );
    let dirs = transfer::SampleSet::new(settings.samples, settings.bands, SEED);
    let occluders = match settings.mode {
        PrtMode::Unshadowed => None,
        _ => Some(transfer::Occluders::build(scene, &statics, &first_vertex)),
    };
    let mut rays = 0u64;
    let direct = transfer::direct(&verts, &dirs, occluders.as_ref(), &mut rays);
    let data = match (settings.effective_bounces(), &occluders) {
        (b, Some(occ)) if settings.mode == PrtMode::Interreflected => {
            interreflect::bounces(&verts, &dirs, occ, &direct, b, &mut rays)
        }
        _ => direct,
    };
    let secs = t0.elapsed().as_secs_f64();
    log::info!(
        "prt: {:?} transfer done in {secs:.2} s ({rays} visibility rays, {:.2} Mrays/s)",
        settings.mode,
        if secs > 0.0 { rays as f64 / secs / 1e6 } else { 0.0 }
    );
    Ok(PrtTransfer { settings: *settings, first_vertex, data, rays })
}

#[cfg(test)]
mod tests;
