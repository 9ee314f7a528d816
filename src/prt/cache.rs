//! The transfer's disk cache, `<dir>/<key>.prt`. The key hashes (FNV-1a 64) the format version, the
//! settings, each static instance's world matrix, positions, normals and indices, and (interreflected
//! transfer only) the materials' albedo. Written to a temporary name and renamed (atomic on one file
//! system); a short, corrupt or foreign file is recomputed with a warning, never trusted.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context as _, Result};

use super::{compute, static_instances, PrtMode, PrtSettings, PrtTransfer, FORMAT_VERSION};
use crate::scene::Scene;

/// Overrides the cache directory (as does `--prt-cache DIR`).
pub const CACHE_DIR_ENV: &str = "HYBRID_RT_PRT_CACHE";
const MAGIC: &[u8; 8] = b"HRTPRT\0\x01";

/// `$HYBRID_RT_PRT_CACHE`, else `$XDG_CACHE_HOME/hybrid-rt/prt`, else
/// `~/.cache/hybrid-rt/prt`; `None` without any of them.
pub fn default_cache_dir() -> Option<PathBuf> {
    user_cache_dir(CACHE_DIR_ENV, "prt")
}

pub use crate::disk_cache::user_cache_dir;

/// How a transfer was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CacheOutcome {
    /// Read from the cache file, nothing computed.
    Loaded,
    /// Computed (no file, or a bad one) and written.
    Computed,
}

/// The cache at one directory (`None`: compute every time).
#[derive(Clone, Debug, Default)]
pub struct PrtCache {
    pub dir: Option<PathBuf>,
}

struct Fnv(u64);
impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
}

/// The cache key of `scene`'s static geometry under `s`.
pub fn key(scene: &Scene, s: &PrtSettings) -> u64 {
    let mut h = Fnv::new();
    for v in [FORMAT_VERSION as u64, s.mode.code() as u64, s.bands as u64, s.samples as u64] {
        h.u64(v);
    }
    h.u64(s.effective_bounces() as u64);
    let statics = static_instances(scene);
    h.u64(statics.len() as u64);
    for i in statics {
        let inst = &scene.instances[i];
        let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
        h.bytes(bytemuck::cast_slice(&inst.world.to_cols_array()));
        h.u64(prim.vertices.len() as u64);
        for v in &prim.vertices {
            h.bytes(bytemuck::cast_slice(&v.position));
            h.bytes(bytemuck::cast_slice(&v.normal));
        }
        h.u64(prim.indices.len() as u64);
        h.bytes(bytemuck::cast_slice(&prim.indices));
        if s.mode == PrtMode::Interreflected {
            let albedo =
                scene.materials.get(scene.instance_material(inst)).map_or([0.0; 4], |m| m.base_color);
            h.bytes(bytemuck::cast_slice(&albedo));
        }
    }
    h.0
}

impl PrtCache {
    pub fn new(dir: Option<PathBuf>) -> Self {
        Self { dir }
    }

    pub fn path(&self, key: u64) -> Option<PathBuf> {
        self.dir.as_ref().map(|d| d.join(format!("{key:016x}.prt")))
    }

    /// The transfer of `scene` under `s`: loaded when a valid file exists,
    /// else computed and (when there is a directory) written.
    pub fn get(&self, scene: &Scene, s: &PrtSettings) -> Result<(PrtTransfer, CacheOutcome)> {
        s.check()?;
        let key = key(scene, s);
        let statics = static_instances(scene);
        let mut first_vertex = vec![None; scene.instances.len()];
        let mut vertices = 0u32;
        for &i in &statics {
            first_vertex[i] = Some(vertices);
            let inst = &scene.instances[i];
            vertices += scene.meshes[inst.mesh].primitives[inst.primitive].vertices.len() as u32;
        }
        let floats = vertices as usize * s.bands * s.bands * s.mode.channels();
        if let Some(path) = self.path(key) {
            if path.exists() {
                let t = Instant::now();
                match read(&path, key, floats) {
                    Ok(data) => {
                        log::info!(
                            "prt: loaded {:?} transfer of {vertices} vertices from {} in {:.1} ms",
                            s.mode,
                            path.display(),
                            t.elapsed().as_secs_f64() * 1e3
                        );
                        let t = PrtTransfer { settings: *s, first_vertex, data, rays: 0 };
                        return Ok((t, CacheOutcome::Loaded));
                    }
                    Err(e) => log::warn!("prt: ignoring cache file {}: {e:#}; recomputing", path.display()),
                }
            }
        }
        let t = compute(scene, s)?;
        if let Some(path) = self.path(key) {
            // A cache that cannot be written costs a recompute next time,
            // not this run.
            if let Err(e) = write(&path, key, &t.data) {
                log::warn!("prt: cannot write cache file {}: {e:#}", path.display());
            }
        }
        Ok((t, CacheOutcome::Computed))
    }
}

/// MAGIC, key (u64), float count (u64), the floats (f32 LE), FNV of them.
fn write(path: &Path, key: u64, data: &[f32]) -> Result<()> {
    let dir = path.parent().context("cache path has no directory")?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut bytes = Vec::with_capacity(32 + data.len() * 4);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&key.to_le_bytes());
    bytes.extend_from_slice(&(data.len() as u64).to_le_bytes());
    for f in data {
        bytes.extend_from_slice(&f.to_le_bytes());
    }
    let mut h = Fnv::new();
    h.bytes(&bytes[24..]);
    bytes.extend_from_slice(&h.0.to_le_bytes());
    let tmp = path.with_extension(format!("prt.tmp{}", std::process::id()));
    std::fs::write(&tmp, &bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
}

fn read(path: &Path, key: u64, floats: usize) -> Result<Vec<f32>> {
    let bytes = std::fs::read(path).context("reading")?;
    let want = 24 + floats * 4 + 8;
    anyhow::ensure!(bytes.len() == want, "{} bytes, expected {want}", bytes.len());
    anyhow::ensure!(&bytes[..8] == MAGIC, "not a PRT cache file of this version");
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap_or_default());
    anyhow::ensure!(u64_at(8) == key, "key {:016x}, expected {key:016x}", u64_at(8));
    anyhow::ensure!(u64_at(16) == floats as u64, "{} floats, expected {floats}", u64_at(16));
    let mut h = Fnv::new();
    h.bytes(&bytes[24..want - 8]);
    anyhow::ensure!(h.0 == u64_at(want - 8), "checksum mismatch");
    let data: Vec<f32> =
        bytes[24..want - 8].chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    anyhow::ensure!(data.iter().all(|f| f.is_finite()), "non-finite transfer values");
    Ok(data)
}
