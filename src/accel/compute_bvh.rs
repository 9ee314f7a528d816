//! The compute backend's acceleration structure: our own BVHs laid out for glsl/trace/compute.glsl.
//! Static instances (never skinned or animated) form one world-space tree with triangles in leaf order
//! ([`FlatStatic`], traced first); the rest keep a two-level BVH: per primitive a 4-wide static tree
//! (rigid: SBVH up to a size, `StaticBuilder`) or binned SAH (skinned, triangles read from the shared
//! vertex/index buffer), and a top level.
//!
//! An update needs no host round-trip: [`ComputeBvh::prepare_update`] rebuilds policy-marked trees on
//! the CPU (staged in the ring slot) and the top-level topology from bounds the host knows (refit
//! roots read back, two frames old with frames in flight); [`ComputeBvh::record_update`] records the
//! skinned refit and the GPU fit of the top level to this frame's roots ([`TopLevelRefit`]);
//! [`ComputeBvh::finish_update`] takes the roots after the fence. Topology only decides speed; the
//! bounds traced are always this frame's.

use anyhow::{Context as _, Result};
use ash::vk;
use glam::{DMat4, Mat4};

use super::bvh::{triangle_aabbs, Bvh, BvhNode, WideBvh, WideNode};
use super::compute_refit::ComputeRefit;
use super::compute_top_level::{host_buffer, TopLevelRefit};
use super::cpu_trace::triangle_positions;
use super::dynamic::{RebuildPolicy, RefitState, Update};
use super::flat::{FlatStatic, FlatTriangle};
use super::flat_cache;
use super::{instance_mask, instance_opaque};
use crate::gpu::origin::RenderOrigin;
use crate::gpu::scene::GpuScene;
use crate::gpu::shared::{BVH_FLAT_ROOT, BVH_WIDE_HEADER};
use crate::scene::{Aabb, Instance, Scene};
use crate::vk::frame_ring::{FrameRing, Source, Uploads};
use crate::vk::pipeline::{Binding, DescriptorSet};
use crate::vk::{built, memory_barrier, Buffer, Context};

/// Mirrors `BvhInstance` in glsl/trace/compute.glsl and
/// glsl/anim/tlas_refit.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBvhInstance {
    pub world_to_object: [f32; 16],
    pub node_offset: u32,
    pub prim_offset: u32,
    pub mask: u32,
    pub opaque: u32,
    /// For the GPU top-level fit: the matrix the host's fit uses.
    pub object_to_world: [f32; 16],
}
const _: () =
    assert!(std::mem::size_of::<GpuBvhInstance>() == crate::gpu::shared::BVH_INSTANCE_STRIDE as usize);
const _: () = assert!(std::mem::size_of::<BvhNode>() == crate::gpu::shared::BVH_NODE_STRIDE as usize);

/// A node no ray can enter: stands in for an empty level.
const EMPTY_NODE: BvhNode = BvhNode { min: [1e30; 3], left_or_first: 0, max: [-1e30; 3], count: 1 };

struct BlasRef {
    bvh: Bvh,
    node_offset: u32,
    prim_offset: u32,
}

/// A skinned instance's BVH: refit on the GPU every frame, rebuilt on the
/// CPU when the policy says so. Its node region is sized for any tree over
/// its triangles, so a rebuild never moves it.
struct SkinnedBvh {
    blas: BlasRef,
    state: RefitState,
}

pub struct ComputeBvh {
    /// Per mesh, per primitive (None for empty primitives).
    blas: Vec<Vec<Option<BlasRef>>>,
    /// Per skinned slot.
    skinned: Vec<SkinnedBvh>,
    refit: Option<ComputeRefit>,
    /// The top level's GPU fit; only with skinned trees (a rigid-only top
    /// level is exact from the host).
    top_refit: Option<TopLevelRefit>,
    blas_nodes: Buffer,
    blas_prims: Buffer,
    /// The flat tree's triangles (`FlatTriangle`, leaf order).
    flat_tris: Buffer,
    /// The flat tree's [first triangle number, instance] per member (`FlatStatic::members`).
    flat_members: Buffer,
    /// Per scene instance: whether the flat tree holds it (then it is not
    /// in the top level), with the world matrix it was flattened at.
    flattened: Vec<Option<DMat4>>,
    /// SAH cost of the flat tree's binary source.
    flat_sah: f32,
    tlas_nodes: Buffer,
    tlas_prims: Buffer,
    instances: Buffer,
    /// The host's copy of the top level last written (topology; bounds as
    /// the host knew them).
    tlas: Bvh,
    pub set: DescriptorSet,
    pub build_ms: f64,
    pub triangles: usize,
    /// Host ms of the last `prepare_update`: CPU tree rebuilds, top level.
    pub rebuild_ms: f64,
    pub top_level_ms: f64,
    /// The GPU scene's render origin (instance transforms are relative to it).
    origin: RenderOrigin,
}

fn append(nodes: &mut Vec<BvhNode>, prims: &mut Vec<u32>, bvh: Bvh, capacity: usize) -> BlasRef {
    let r = BlasRef { node_offset: nodes.len() as u32, prim_offset: prims.len() as u32, bvh };
    nodes.extend_from_slice(&r.bvh.nodes);
    nodes.resize(r.node_offset as usize + capacity.max(r.bvh.nodes.len()), EMPTY_NODE);
    prims.extend_from_slice(&r.bvh.prim_indices);
    r
}

/// A static BLAS as a 4-wide tree: a binary header node (root bounds for the first box test and the
/// GPU top-level fit; `count` = BVH_WIDE_HEADER), then the 64-byte wide nodes from an even slot so
/// the shader indexes them as an array.
fn append_wide(nodes: &mut Vec<BvhNode>, prims: &mut Vec<u32>, bvh: Bvh) -> BlasRef {
    let wide = WideBvh::from_binary(&bvh);
    let r = BlasRef {
        node_offset: push_wide_nodes(nodes, bvh.nodes.first(), &wide.nodes),
        prim_offset: prims.len() as u32,
        bvh,
    };
    prims.extend_from_slice(&wide.prim_indices);
    r
}

/// Appends `wide`'s header (at an odd slot) and nodes; returns the header's
/// slot. An empty tree gets an unenterable header and no nodes.
fn push_wide_nodes(nodes: &mut Vec<BvhNode>, root: Option<&BvhNode>, wide: &[WideNode]) -> u32 {
    if nodes.len().is_multiple_of(2) {
        nodes.push(EMPTY_NODE);
    }
    let at = nodes.len() as u32;
    match root {
        Some(root) => {
            nodes.push(BvhNode { min: root.min, left_or_first: 0, max: root.max, count: BVH_WIDE_HEADER });
            nodes.extend_from_slice(bytemuck::cast_slice(wide));
        }
        None => nodes.push(EMPTY_NODE),
    }
    at
}

/// What `build` uploads once: BLAS node slots, BLAS triangle order, the flat
/// tree's triangles.
struct TreeData<'a> {
    nodes: &'a [BvhNode],
    prims: &'a [u32],
    flat_tris: &'a [FlatTriangle],
    flat_members: &'a [[u32; 2]],
}

impl ComputeBvh {
    pub fn build(ctx: &Context, scene: &Scene, gpu: &GpuScene) -> Result<ComputeBvh> {
        let t0 = std::time::Instant::now();
        crate::progress::stage("building the compute BVH");
        let mut nodes: Vec<BvhNode> = Vec::new();
        let mut prims: Vec<u32> = Vec::new();
        // The flat tree first: its header at the fixed slot the shader reads.
        let flat = FlatStatic::build(scene, gpu.origin, flat_cache::default_dir().as_deref())
            .context("the compute BVH's flat tree")?;
        let flat_at = push_wide_nodes(&mut nodes, flat.root.as_ref(), &flat.nodes);
        assert_eq!(flat_at, BVH_FLAT_ROOT, "the flat tree's header slot");
        let flat_ms = t0.elapsed().as_secs_f64() * 1e3;
        let mut triangles = flat.source_triangles;
        // Primitives drawn only skinned, only flattened (or not at all) get
        // no tree of their own.
        let mut used: Vec<Vec<bool>> = scene.meshes.iter().map(|m| vec![false; m.primitives.len()]).collect();
        for (inst, _) in
            scene.instances.iter().zip(&flat.flattened).filter(|(i, f)| i.skinned.is_none() && !**f)
        {
            used[inst.mesh][inst.primitive] = true;
        }
        let wanted: Vec<(usize, usize)> = scene
            .meshes
            .iter()
            .zip(&used)
            .enumerate()
            .flat_map(|(m, (mesh, used))| {
                mesh.primitives
                    .iter()
                    .zip(used)
                    .enumerate()
                    .filter(|(_, (p, used))| p.indices.len() >= 3 && **used)
                    .map(move |(i, _)| (m, i))
            })
            .collect();
        let size = |&(m, i): &(usize, usize)| scene.meshes[m].primitives[i].indices.len();
        // Biggest first: Sponza's largest primitives take most of the time.
        let mut order: Vec<usize> = (0..wanted.len()).collect();
        order.sort_by_key(|&k| std::cmp::Reverse(size(&wanted[k])));
        // Built once, so the split BVH's better trees are worth its slower build, on every core. Not
        // refittable (leaf boxes hold clipped parts).
        let trees = crate::par::map(wanted.len(), &order, |k| {
            let (m, i) = wanted[k];
            let p = &scene.meshes[m].primitives[i];
            Bvh::build_static(&triangle_positions(&p.vertices, &p.indices)).0
        })
        .context("building the static BLASes")?;
        let mut blas: Vec<Vec<Option<BlasRef>>> =
            scene.meshes.iter().map(|m| m.primitives.iter().map(|_| None).collect()).collect();
        for (&(m, i), bvh) in wanted.iter().zip(trees) {
            // Collapsed 4-wide: fewer, wider node fetches.
            blas[m][i] = Some(append_wide(&mut nodes, &mut prims, bvh));
        }
        let static_ms = t0.elapsed().as_secs_f64() * 1e3 - flat_ms;
        // Skinned: trees over the CPU pose (what the GPU vertex range holds at upload); binned SAH, fast to
        // rebuild and refittable (leaf boxes hold whole triangles).
        let world = scene.world_matrices();
        let mut skinned = Vec::new();
        for inst in &scene.instances {
            let Some(posed) = scene.skinned_pose(inst, &world) else { continue };
            let indices = &scene.meshes[inst.mesh].primitives[inst.primitive].indices;
            triangles += indices.len() / 3;
            let aabbs = triangle_aabbs(&posed, indices);
            let bvh = Bvh::build(&aabbs);
            let state = RefitState::new(&bvh.root_bounds());
            let capacity = (2 * aabbs.len()).saturating_sub(1);
            let blas = append(&mut nodes, &mut prims, bvh, capacity);
            skinned.push(SkinnedBvh { blas, state });
        }
        let blas_ms = t0.elapsed().as_secs_f64() * 1e3;
        // A descriptor needs a buffer.
        if prims.is_empty() {
            prims.push(0);
        }
        // Every GPU object lands in `bvh` as it is made, so an error half-way
        // destroys what exists.
        let bvh = ComputeBvh {
            blas,
            skinned,
            refit: None,
            top_refit: None,
            blas_nodes: Buffer::null(),
            blas_prims: Buffer::null(),
            flat_tris: Buffer::null(),
            flat_members: Buffer::null(),
            flattened: scene
                .instances
                .iter()
                .zip(&flat.flattened)
                .map(|(inst, &f)| f.then_some(inst.world))
                .collect(),
            flat_sah: flat.sah,
            tlas_nodes: Buffer::null(),
            tlas_prims: Buffer::null(),
            instances: Buffer::null(),
            tlas: Bvh::default(),
            set: DescriptorSet::null(),
            build_ms: 0.0,
            triangles,
            rebuild_ms: 0.0,
            top_level_ms: 0.0,
            origin: gpu.origin,
        };
        crate::progress::stage("uploading the compute BVH");
        let data = TreeData {
            nodes: &nodes,
            prims: &prims,
            flat_tris: &flat.triangles,
            flat_members: &flat.members,
        };
        let mut bvh = built(ctx, bvh, |bvh| {
            bvh.create_buffers(ctx, scene, gpu, data)?;
            // Fit the skinned trees and top level to the GPU's vertices (the CPU pose may differ in the
            // last bit). A load-time submission, not part of any frame.
            let updates = vec![Update::Refit; bvh.skinned.len()];
            let mut ring = FrameRing::new(1, "compute BVH load")?;
            let fitted = (|| {
                ring.begin(0)?;
                bvh.write_top_level(&mut Uploads { ring: &mut ring, slot: 0 }, scene)?;
                let roots = bvh.roots_source().map(|r| ring.download(0, r)).transpose()?;
                ctx.one_shot("refit skinned BVHs", |cmd| {
                    ring.record_uploads(ctx, cmd, 0)?;
                    bvh.record_update(ctx, cmd);
                    ring.record_downloads(ctx, cmd, 0)
                })?;
                let roots = roots.map(|d| ring.read(0, d)).transpose()?;
                bvh.finish_update(&updates, &RebuildPolicy::default(), roots)
            })();
            ring.destroy(ctx);
            fitted
        })?;
        bvh.build_ms = t0.elapsed().as_secs_f64() * 1e3;
        let flattened = flat.flattened.iter().filter(|f| **f).count();
        let tree_bytes = nodes.len() * std::mem::size_of::<BvhNode>()
            + prims.len() * 4
            + flat.triangles.len() * std::mem::size_of::<FlatTriangle>()
            + flat.members.len() * 8;
        log::info!(
            "compute BVH: {} triangles; {} static instances flattened into one 4-wide tree ({} over {} triangles: {} references, {} wide nodes, SAH cost {:.1}, {}); {} B of nodes + {} B of triangle order + {} B of flat triangles + {} B of flat members = {} B; per-primitive trees: static {:.0} ms (reference-weighted SAH cost {:.1}), skinned binned {:.0} ms; built in {:.0} ms ({:.2} Mtri/s); top level over {} of {} instances, {} refit each frame; with the scene's vertices and indices {:.1} B per triangle",
            triangles,
            flattened,
            flat.builder.name(),
            flat.source_triangles,
            flat.triangles.len(),
            flat.nodes.len(),
            bvh.flat_sah,
            if flat.cached {
                format!("read from the disk cache in {flat_ms:.0} ms")
            } else {
                let [transform, build, collapse, gather] = flat.stages_ms;
                format!(
                    "{flat_ms:.0} ms, {:.2} Mtri/s: transform {transform:.0}, build {build:.0}, collapse 4-wide \
                     {collapse:.0}, gather {gather:.0} ms",
                    flat.source_triangles as f64 / (flat_ms.max(1e-3) * 1e3)
                )
            },
            nodes.len() * std::mem::size_of::<BvhNode>(),
            prims.len() * 4,
            flat.triangles.len() * std::mem::size_of::<FlatTriangle>(),
            flat.members.len() * 8,
            tree_bytes,
            static_ms,
            bvh.mean_sah_cost(),
            blas_ms - static_ms - flat_ms,
            blas_ms,
            triangles as f64 / (blas_ms.max(1e-3) * 1e3),
            scene.instances.len() - flattened,
            scene.instances.len(),
            bvh.skinned.len(),
            (tree_bytes as u64 + gpu.vertices.size + gpu.indices.size) as f64 / triangles.max(1) as f64
        );
        Ok(bvh)
    }

    /// Builds the top-level topology over the bounds the host knows (skinned: last roots read back, or a
    /// CPU rebuild's) and writes it with the instance records; with skinned trees the GPU fit then sets
    /// this frame's bounds. Staged in the ring slot: a frame in flight keeps reading its own.
    fn write_top_level(&mut self, up: &mut Uploads, scene: &Scene) -> Result<()> {
        // Only animation moves instances after loading, and the flat tree
        // holds none that it moves; a moved one would be traced where it was.
        for (i, (inst, at)) in scene.instances.iter().zip(&self.flattened).enumerate() {
            anyhow::ensure!(
                at.is_none_or(|w| w == inst.world),
                "compute BVH: instance {i} (node {}) moved, but it was flattened into the static tree as never animated",
                inst.node
            );
        }
        let (tlas, instances) = top_level(scene, self.origin, |inst| self.blas_of(inst));
        up.write(&self.tlas_nodes, 0, bytemuck::cast_slice(&tlas.nodes))?;
        up.write(&self.tlas_prims, 0, bytemuck::cast_slice(&tlas.prim_indices))?;
        up.write(&self.instances, 0, bytemuck::cast_slice(&instances))?;
        if let Some(t) = &mut self.top_refit {
            // The placeholder of an empty top level must stay unenterable.
            t.set_tree(up, (tlas.nodes[0] != EMPTY_NODE).then_some(&tlas))?;
        }
        self.tlas = tlas;
        Ok(())
    }

    /// Number of skinned trees (refit every frame).
    pub fn skinned_count(&self) -> usize {
        self.skinned.len()
    }

    /// Host work before recording (a frame may be in flight): rebuilds policy-marked skinned trees from
    /// the CPU pose, staged in the ring slot (the GPU refit then fits them to the skinned vertices), and
    /// stages the top level. No submission, no wait. Returns each skinned slot's update for
    /// `finish_update`.
    pub fn prepare_update(
        &mut self,
        up: &mut Uploads,
        scene: &Scene,
        policy: &RebuildPolicy,
    ) -> Result<Vec<Update>> {
        let t0 = std::time::Instant::now();
        let updates: Vec<Update> = self.skinned.iter().map(|s| s.state.next(policy)).collect();
        if updates.contains(&Update::Rebuild) {
            self.rebuild_skinned(up, scene, &updates)?;
        }
        self.rebuild_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = std::time::Instant::now();
        self.write_top_level(up, scene)?;
        self.top_level_ms = t1.elapsed().as_secs_f64() * 1e3;
        Ok(updates)
    }

    fn rebuild_skinned(&mut self, up: &mut Uploads, scene: &Scene, updates: &[Update]) -> Result<()> {
        let world = scene.world_matrices();
        for inst in &scene.instances {
            let Some(slot) = inst.skinned.filter(|s| updates[*s] == Update::Rebuild) else { continue };
            let posed = scene.skinned_pose(inst, &world).expect("skinned slot has a pose");
            let indices = &scene.meshes[inst.mesh].primitives[inst.primitive].indices;
            let bvh = Bvh::build(&triangle_aabbs(&posed, indices));
            let s = &mut self.skinned[slot];
            let b = &s.blas;
            let nodes_at = b.node_offset as usize * std::mem::size_of::<BvhNode>();
            up.write(&self.blas_nodes, nodes_at, bytemuck::cast_slice(&bvh.nodes))?;
            up.write(&self.blas_prims, b.prim_offset as usize * 4, bytemuck::cast_slice(&bvh.prim_indices))?;
            if let Some(refit) = &mut self.refit {
                refit.set_levels(up, slot, &bvh)?;
            }
            s.blas.bvh = bvh;
        }
        Ok(())
    }

    /// Records the skinned refit, then the top level's GPU fit, each with its barrier (the last to the
    /// tracer's reads). Needs `prepare_update` first and skinning recorded before it.
    pub fn record_update(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        self.record_refit(ctx, cmd);
        self.record_top_level(ctx, cmd);
    }

    /// The first half of `record_update` (separate for pass timing).
    pub fn record_refit(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        let Some(refit) = &self.refit else { return };
        // The previous frame's tracing read what this update rewrites.
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        memory_barrier(
            ctx,
            cmd,
            (compute, vk::AccessFlags2::SHADER_STORAGE_READ),
            (compute, vk::AccessFlags2::SHADER_STORAGE_WRITE),
        );
        refit.record(ctx, cmd);
    }

    /// The second half of `record_update`, after `record_refit`.
    pub fn record_top_level(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        if let Some(t) = &self.top_refit {
            t.record(ctx, cmd);
        }
    }

    /// Where the ring's download at the frame's end reads the refit roots
    /// from (None without skinned trees).
    pub fn roots_source(&self) -> Option<Source> {
        self.refit.as_ref().map(|r| r.roots_source())
    }

    /// After the frame's fence: judges the refit roots (`roots`: `roots_source`'s download) for the
    /// rebuild policy and the next topology. A later in-flight frame may already have rebuilt a slot;
    /// its root then comes from the old tree for one frame (topology only decides speed).
    pub fn finish_update(
        &mut self,
        updates: &[Update],
        policy: &RebuildPolicy,
        roots: Option<&[u8]>,
    ) -> Result<()> {
        if let (Some(refit), Some(roots)) = (&self.refit, roots) {
            for ((s, root), u) in self.skinned.iter_mut().zip(refit.roots(roots)).zip(updates) {
                s.blas.bvh.nodes[0] = root;
                s.state.done(*u, &s.blas.bvh.root_bounds(), policy);
            }
        }
        Ok(())
    }

    /// The top level as the GPU left it after the last completed update:
    /// the topology the host wrote, with the bounds the GPU fit (for tests).
    pub fn gpu_top_level(&self) -> Result<Bvh> {
        let nodes: Vec<BvhNode> = bytemuck::pod_collect_to_vec(self.tlas_nodes.read()?);
        Ok(Bvh {
            nodes: nodes[..self.tlas.nodes.len()].to_vec(),
            prim_indices: self.tlas.prim_indices.clone(),
        })
    }

    /// The top level as the host last wrote it: the topology, with the
    /// bounds it estimated before the GPU fit (for tests).
    pub fn host_topology(&self) -> &Bvh {
        &self.tlas
    }

    /// For tests: the topology of the last update refit on the CPU over the read-back roots (the GPU fit's
    /// reference, node for node), and a fresh top-level build over them (the old host path).
    pub fn host_top_level(&self, scene: &Scene) -> (Bvh, Bvh) {
        let blas_of = |inst: &Instance| self.blas_of(inst);
        let bounds: Vec<Aabb> = scene
            .instances
            .iter()
            .map(|inst| {
                world_bounds(scene, inst, &self.origin.matrix(&inst.world), blas_of(inst))
                    .unwrap_or(Aabb::EMPTY)
            })
            .collect();
        let mut refit = self.tlas.clone();
        refit.refit(&bounds);
        (refit, top_level(scene, self.origin, blas_of).0)
    }

    /// An instance's own tree (None for flattened ones: the flat tree
    /// holds them, the top level leaves them out).
    fn blas_of(&self, inst: &Instance) -> Option<&BlasRef> {
        match inst.skinned {
            Some(slot) => self.skinned.get(slot).map(|s| &s.blas),
            None => self.blas[inst.mesh][inst.primitive].as_ref(),
        }
    }

    /// How many scene instances the flat static tree holds.
    pub fn flattened_count(&self) -> usize {
        self.flattened.iter().filter(|f| f.is_some()).count()
    }

    /// SAH cost of the static per-primitive BVHs, averaged with reference
    /// counts (triangles, plus the SBVH's duplicates) as weights.
    /// Bytes of the tracer's buffers: nodes, triangle order, flat triangles and members, top level and
    /// instance records.
    pub fn bytes(&self) -> u64 {
        self.trace_buffers().iter().map(|b| b.size).sum()
    }

    /// The trace set's buffers, in binding order (BVH_BLAS_NODES .. BVH_FLAT_MEMBERS).
    fn trace_buffers(&self) -> [&Buffer; 7] {
        [
            &self.blas_nodes,
            &self.blas_prims,
            &self.tlas_nodes,
            &self.tlas_prims,
            &self.instances,
            &self.flat_tris,
            &self.flat_members,
        ]
    }

    pub fn mean_sah_cost(&self) -> f32 {
        let (mut sum, mut weight) = (0.0f64, 0.0f64);
        for b in self.blas.iter().flatten().flatten() {
            let n = b.bvh.prim_indices.len() as f64;
            sum += b.bvh.sah_cost() as f64 * n;
            weight += n;
        }
        (sum / weight.max(1.0)) as f32
    }

    /// The GPU half of `build`: node and triangle-order buffers, refit
    /// passes, top-level buffers and the trace set.
    fn create_buffers(&mut self, ctx: &Context, scene: &Scene, gpu: &GpuScene, data: TreeData) -> Result<()> {
        let TreeData { nodes, prims, flat_tris, flat_members } = data;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        self.blas_nodes = Buffer::with_data(ctx, "BVH BLAS nodes", bytemuck::cast_slice(nodes), storage)?;
        self.blas_prims =
            Buffer::with_data(ctx, "BVH BLAS triangle order", bytemuck::cast_slice(prims), storage)?;
        // Never empty: a descriptor needs a buffer.
        let placeholder = [FlatTriangle::default()];
        let flat_tris = if flat_tris.is_empty() { &placeholder[..] } else { flat_tris };
        self.flat_tris =
            Buffer::with_data(ctx, "BVH flat static triangles", bytemuck::cast_slice(flat_tris), storage)?;
        let flat_members = if flat_members.is_empty() { &[[0u32; 2]][..] } else { flat_members };
        self.flat_members =
            Buffer::with_data(ctx, "BVH flat tree members", bytemuck::cast_slice(flat_members), storage)?;
        if !self.skinned.is_empty() {
            let refs: Vec<_> =
                self.skinned.iter().map(|s| (&s.blas.bvh, s.blas.node_offset, s.blas.prim_offset)).collect();
            self.refit = Some(ComputeRefit::new(ctx, gpu, &refs, &self.blas_nodes, &self.blas_prims)?);
        }
        let n = scene.instances.len().max(1);
        self.tlas_nodes = host_buffer(ctx, "BVH top-level nodes", 2 * n * std::mem::size_of::<BvhNode>())?;
        self.tlas_prims = host_buffer(ctx, "BVH top-level instance order", 4 * n)?;
        self.instances = host_buffer(ctx, "BVH instances", n * std::mem::size_of::<GpuBvhInstance>())?;
        if self.refit.is_some() {
            self.top_refit = Some(TopLevelRefit::new(
                ctx,
                n,
                &self.tlas_nodes,
                &self.tlas_prims,
                &self.instances,
                &self.blas_nodes,
            )?);
        }
        let sb = Binding::one(vk::DescriptorType::STORAGE_BUFFER);
        self.set = DescriptorSet::new(ctx, "trace set (compute BVH)", &[sb; 7])?;
        for (i, b) in self.trace_buffers().iter().enumerate() {
            self.set.write_buffer(ctx, i as u32, b.raw);
        }
        Ok(())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for b in [
            &mut self.blas_nodes,
            &mut self.blas_prims,
            &mut self.flat_tris,
            &mut self.flat_members,
            &mut self.tlas_nodes,
            &mut self.tlas_prims,
            &mut self.instances,
        ] {
            b.destroy(ctx);
        }
        if let Some(r) = &mut self.refit {
            r.destroy(ctx);
        }
        if let Some(t) = &mut self.top_refit {
            t.destroy(ctx);
        }
        self.set.destroy(ctx);
    }
}

/// World bounds of `inst`'s tree, if some ray can hit it.
fn world_bounds(scene: &Scene, inst: &Instance, world: &Mat4, b: Option<&BlasRef>) -> Option<Aabb> {
    let n = b?.bvh.nodes.first()?;
    if instance_mask(scene, inst) == 0 {
        return None;
    }
    let world = Aabb { min: n.min.into(), max: n.max.into() }.transformed(world);
    (world.min.is_finite() && world.max.is_finite()).then_some(world)
}

/// The top level over all instances (rebuilt whenever instances move) and
/// the per-instance records the shader needs.
fn top_level<'a>(
    scene: &Scene,
    origin: RenderOrigin,
    blas_of: impl Fn(&Instance) -> Option<&'a BlasRef>,
) -> (Bvh, Vec<GpuBvhInstance>) {
    let mut records = Vec::with_capacity(scene.instances.len());
    // Only instances some ray can hit enter the top level; `traceable` maps
    // its primitive indices back to instance indices.
    let mut bounds = Vec::with_capacity(scene.instances.len());
    let mut traceable = Vec::with_capacity(scene.instances.len());
    for (i, inst) in scene.instances.iter().enumerate() {
        let b = blas_of(inst);
        // Relative to the render origin, like every GPU transform.
        let world = origin.matrix(&inst.world);
        let world_to_object = if world.determinant().abs() > f32::MIN_POSITIVE {
            world.inverse()
        } else {
            Mat4::ZERO // a zero-scale instance can never be hit
        };
        let mask = if b.is_some() { instance_mask(scene, inst) as u32 } else { 0 };
        records.push(GpuBvhInstance {
            world_to_object: world_to_object.to_cols_array(),
            node_offset: b.map(|b| b.node_offset).unwrap_or(0),
            prim_offset: b.map(|b| b.prim_offset).unwrap_or(0),
            mask,
            opaque: instance_opaque(scene, inst) as u32,
            object_to_world: world.to_cols_array(),
        });
        if let Some(world) = world_bounds(scene, inst, &world, b) {
            bounds.push(world);
            traceable.push(i as u32);
        }
    }
    let mut tlas = Bvh::build(&bounds);
    for p in &mut tlas.prim_indices {
        *p = traceable[*p as usize];
    }
    if tlas.nodes.is_empty() {
        tlas.nodes.push(EMPTY_NODE);
        tlas.prim_indices.push(0);
    }
    if records.is_empty() {
        records.push(GpuBvhInstance::default());
    }
    (tlas, records)
}

crate::destroy_by_method!(ComputeBvh);
