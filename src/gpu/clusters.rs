//! The G-buffer's clusters for occlusion culling (render/occlusion.rs): each rigid draw split into runs
//! of at most CLUSTER_TRIANGLES triangles with an object-space box. On the GPU: the clusters, one
//! indirect draw per cluster and phase (the cull pass sets instance count 0 or 1; first instance is
//! the cluster index), last frame's visibility, and the counters. Built on the first culled frame
//! (GpuScene::ensure_clusters), not at upload.
//!
//! A skinned instance is one cluster with an empty box (bind-pose boxes would be wrong), drawn whole
//! in phase 1, where it occludes like everything drawn there.

use anyhow::Result;
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use gpu_allocator::MemoryLocation;

use super::draw::Draw;
use super::shared::{CLUSTER_STRIDE, CLUSTER_TRIANGLES, OCC_COUNTER_SLOTS};
use crate::scene::{Aabb, Scene};
use crate::vk::{built, Buffer, Context};

/// One cluster as the shaders see it (glsl/common/cluster.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuCluster {
    pub min: [f32; 3],
    pub instance: u32,
    pub max: [f32; 3],
}
const _: () = assert!(std::mem::size_of::<GpuCluster>() == CLUSTER_STRIDE as usize);

/// VkDrawIndirectCommand: clusters are drawn non-indexed, the vertex stage fetching index and vertex
/// itself (glsl/common/gbuffer_draw.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DrawCommand {
    pub vertex_count: u32,
    pub instance_count: u32,
    pub first_vertex: u32,
    pub first_instance: u32,
}

/// The byte stride of `DrawCommand` in the indirect buffer.
pub const COMMAND_STRIDE: u32 = std::mem::size_of::<DrawCommand>() as u32;

/// The clusters of every draw, on the host.
#[derive(Clone, Debug, Default)]
pub struct ClusterList {
    pub clusters: Vec<GpuCluster>,
    pub commands: Vec<DrawCommand>,
    /// Per draw (index into `GpuScene::draws`): its first cluster and
    /// cluster count.
    pub ranges: Vec<(u32, u32)>,
}

/// Splits rigid draws into runs of at most `per_cluster` triangles, ending a run early where the next
/// triangle would stretch its box past 1/32 of the scene diagonal: index order is not always spatially
/// coherent (Sponza's 128-triangle runs had a median box of 2 m in a 51 m scene), and a long box is
/// almost never hidden.
pub fn build(scene: &Scene, draws: &[Draw], per_cluster: u32) -> ClusterList {
    let mut out = ClusterList::default();
    let world_limit = (scene.bounds.max - scene.bounds.min).length() / 32.0;
    for d in draws {
        let inst = &scene.instances[d.instance as usize];
        let skinned = inst.skinned.is_some();
        let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
        let m = inst.world;
        let scale = [m.x_axis, m.y_axis, m.z_axis].iter().map(|a| a.truncate().length()).fold(0.0, f64::max);
        let limit =
            if scale > 0.0 && world_limit.is_finite() { world_limit / scale as f32 } else { f32::INFINITY };
        let first = out.clusters.len() as u32;
        let triangles = d.range.index_count / 3;
        let mut t = 0;
        while t < triangles {
            let mut n = 0;
            let mut b = Aabb::EMPTY;
            while t + n < triangles && (skinned || n < per_cluster) {
                if skinned {
                    n = triangles - t;
                    break;
                }
                let mut grown = b;
                for &i in &prim.indices[((t + n) * 3) as usize..((t + n) * 3 + 3) as usize] {
                    grown.grow(Vec3::from(prim.vertices[i as usize].position));
                }
                if n > 0 && (grown.max - grown.min).length() > limit {
                    break;
                }
                b = grown;
                n += 1;
            }
            out.commands.push(DrawCommand {
                vertex_count: n * 3,
                instance_count: 0,
                first_vertex: d.range.first_index + t * 3,
                first_instance: 0,
            });
            out.clusters.push(GpuCluster { min: b.min.into(), instance: d.instance, max: b.max.into() });
            t += n;
        }
        out.ranges.push((first, out.clusters.len() as u32 - first));
    }
    out
}

/// The clusters on the GPU.
pub struct Clusters {
    pub list: ClusterList,
    pub clusters: Buffer,
    /// Phase 1's commands, then phase 2's (`list.commands` twice).
    pub commands: Buffer,
    /// One word per cluster: visible at the end of the previous frame.
    pub visible: Buffer,
    /// OCC_COUNTER_SLOTS words, host-visible.
    pub counters: Buffer,
}

impl Clusters {
    pub fn null() -> Clusters {
        Clusters {
            list: ClusterList::default(),
            clusters: Buffer::null(),
            commands: Buffer::null(),
            visible: Buffer::null(),
            counters: Buffer::null(),
        }
    }

    pub fn upload(ctx: &Context, scene: &Scene, draws: &[Draw]) -> Result<Clusters> {
        built(ctx, Clusters::null(), |c| c.fill(ctx, scene, draws))
    }

    fn fill(&mut self, ctx: &Context, scene: &Scene, draws: &[Draw]) -> Result<()> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        self.list = build(scene, draws, CLUSTER_TRIANGLES);
        let l = &self.list;
        // A placeholder word keeps empty buffers valid to bind.
        let bytes = |b: &[u8]| if b.is_empty() { vec![0u8; 4] } else { b.to_vec() };
        self.clusters =
            Buffer::with_data(ctx, "clusters", &bytes(bytemuck::cast_slice(&l.clusters)), storage)?;
        let both: Vec<DrawCommand> = l.commands.iter().chain(&l.commands).copied().collect();
        self.commands = Buffer::with_data(
            ctx,
            "cluster draws (phase 1, phase 2)",
            &bytes(bytemuck::cast_slice(&both)),
            storage | vk::BufferUsageFlags::INDIRECT_BUFFER,
        )?;
        // Nothing was visible before the first frame: phase 2 draws it all.
        let zeros = vec![0u8; 4 * l.clusters.len().max(1)];
        self.visible = Buffer::with_data(ctx, "cluster visibility", &zeros, storage)?;
        self.counters = Buffer::new(
            ctx,
            "occlusion counters",
            4 * OCC_COUNTER_SLOTS as u64,
            storage,
            MemoryLocation::GpuToCpu,
        )?;
        self.counters.write(0, &[0u8; 4 * OCC_COUNTER_SLOTS as usize])
    }

    /// The last culled frame's counters: clusters drawn in phase 1, in phase 2, occluded, outside the
    /// frustum (of all clusters, also of draws the host left out); triangles drawn.
    pub fn counts(&self) -> Result<[u32; OCC_COUNTER_SLOTS as usize]> {
        let words: &[u32] = bytemuck::cast_slice(&self.counters.read()?[..4 * OCC_COUNTER_SLOTS as usize]);
        Ok(words.try_into()?)
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for b in [&mut self.clusters, &mut self.commands, &mut self.visible, &mut self.counters] {
            b.destroy(ctx);
        }
    }
}

crate::destroy_by_method!(Clusters);
