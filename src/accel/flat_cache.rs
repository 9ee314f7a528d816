//! The flat tree's disk cache, `<dir>/<key>.bvh` (issue 36 item 3): a scene loaded again with the same
//! static geometry reads its compute BVH instead of building it (a split BVH over Sponza takes ~3 s
//! on the 2-core VM, the binned tree over a 4 M triangle terrain ~2 s). The key hashes the format
//! version (bump it when a builder, the node layout or `FlatTriangle` changes), the builder choice
//! line, the render origin and each flattened instance's index, ray mask and opacity, world matrix,
//! vertices and indices; the file is checked whole (`disk_cache`) and a bad one is rebuilt with a
//! warning.
//!
//! Directory: `$HYBRID_RT_BVH_CACHE`, else `$XDG_CACHE_HOME/hybrid-rt/bvh`, else
//! `~/.cache/hybrid-rt/bvh`; `HYBRID_RT_BVH_CACHE=off` turns it off.

use std::path::{Path, PathBuf};

use anyhow::{ensure, Context as _, Result};

use super::bvh::{BvhNode, StaticBuilder, WideNode, DEFAULT_ALPHA, SBVH_MAX_TRIANGLES};
use super::flat::{FlatStatic, FlatTriangle};
use crate::disk_cache::{self, Hash64};
use crate::gpu::origin::RenderOrigin;
use crate::scene::Scene;

/// Overrides the cache directory; `off` turns the cache off.
pub const CACHE_DIR_ENV: &str = "HYBRID_RT_BVH_CACHE";
/// Trees over fewer triangles build in well under 0.1 s: not worth a file.
pub const CACHE_MIN_TRIANGLES: usize = 1 << 16;
/// The builders' and layouts' version: part of the key and the magic.
const FORMAT_VERSION: u64 = 2;
const MAGIC: &[u8; 8] = b"HRTBVH\0\x02";

/// The directory by the platform convention, `None` when turned off (or no home).
pub fn default_dir() -> Option<PathBuf> {
    if std::env::var_os(CACHE_DIR_ENV).is_some_and(|v| v == "off") {
        return None;
    }
    disk_cache::user_cache_dir(CACHE_DIR_ENV, "bvh")
}

pub fn path(dir: &Path, key: u64) -> PathBuf {
    dir.join(format!("{key:016x}.bvh"))
}

/// The key of the flat tree over `members` (instance indices) of `scene` with triangle id `flags`
/// (ray mask and opacity: `flat::member_flags`).
pub fn key(scene: &Scene, origin: RenderOrigin, members: &[usize], flags: &[u32]) -> u64 {
    let mut h = Hash64::default();
    for v in [FORMAT_VERSION, SBVH_MAX_TRIANGLES as u64, DEFAULT_ALPHA.to_bits() as u64, members.len() as u64]
    {
        h.u64(v);
    }
    h.bytes(bytemuck::cast_slice(&origin.0.to_array()));
    for &i in members {
        let inst = &scene.instances[i];
        let p = &scene.meshes[inst.mesh].primitives[inst.primitive];
        h.u64(i as u64);
        h.u64(flags[i] as u64);
        h.bytes(bytemuck::cast_slice(&inst.world.to_cols_array()));
        // Lengths first: the hash streams, so the field boundaries must be in it.
        h.u64(p.vertices.len() as u64);
        h.bytes(bytemuck::cast_slice(&p.vertices));
        h.u64(p.indices.len() as u64);
        h.bytes(bytemuck::cast_slice(&p.indices));
    }
    h.finish()
}

/// Header words: builder, whether there is a root, source triangles, SAH cost bits, node count,
/// triangle count; then the root node, the wide nodes and the triangles.
const HEADER: usize = 6 * 8 + std::mem::size_of::<BvhNode>();

pub fn store(path: &Path, key: u64, flat: &FlatStatic) -> Result<()> {
    let builder = match flat.builder {
        StaticBuilder::Sbvh => 0u64,
        StaticBuilder::Binned => 1,
    };
    let mut header = Vec::with_capacity(HEADER);
    for v in [
        builder,
        flat.root.is_some() as u64,
        flat.source_triangles as u64,
        flat.sah.to_bits() as u64,
        flat.nodes.len() as u64,
        flat.triangles.len() as u64,
    ] {
        header.extend_from_slice(&v.to_le_bytes());
    }
    header.extend_from_slice(bytemuck::bytes_of(&flat.root.unwrap_or_default()));
    let parts = [&header[..], bytemuck::cast_slice(&flat.nodes), bytemuck::cast_slice(&flat.triangles)];
    disk_cache::write(path, MAGIC, key, &parts)
}

/// The tree in the file at `path`, with `flattened` and `members` (which the key covers) as its
/// instance lists. Read straight into the tree's vectors.
pub fn load(path: &Path, key: u64, flattened: Vec<bool>, members: Vec<[u32; 2]>) -> Result<FlatStatic> {
    let mut r = disk_cache::Reader::open(path, MAGIC, key)?;
    let mut header = [0u8; HEADER];
    r.read(&mut header)?;
    let word = |k: usize| u64::from_le_bytes(header[8 * k..8 * k + 8].try_into().unwrap_or_default());
    let builder = match word(0) {
        0 => StaticBuilder::Sbvh,
        1 => StaticBuilder::Binned,
        b => anyhow::bail!("unknown builder {b}"),
    };
    let (nodes, tris) = (word(4), word(5));
    let size = |n: u64, each: usize| n.checked_mul(each as u64).context("count overflows");
    let bytes = size(nodes, std::mem::size_of::<WideNode>())?
        .checked_add(size(tris, std::mem::size_of::<FlatTriangle>())?)
        .context("count overflows")?;
    // Checked before allocating: a damaged count must not ask for terabytes.
    ensure!(bytes == r.left(), "{} payload bytes for {nodes} nodes and {tris} triangles", r.left());
    let mut wide = vec![WideNode::default(); nodes as usize];
    r.read(bytemuck::cast_slice_mut(&mut wide))?;
    let mut triangles = vec![FlatTriangle::default(); tris as usize];
    r.read(bytemuck::cast_slice_mut(&mut triangles))?;
    r.finish()?;
    Ok(FlatStatic {
        root: (word(1) != 0).then(|| bytemuck::pod_read_unaligned(&header[48..HEADER])),
        sah: f32::from_bits(word(3) as u32),
        builder,
        nodes: wide,
        members,
        triangles,
        source_triangles: word(2) as usize,
        flattened,
        cached: true,
        stages_ms: [0.0; 4],
    })
}
