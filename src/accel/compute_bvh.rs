//! The compute backend's acceleration structure: our own two-level BVH
//! (one binned-SAH BVH per mesh primitive + a top level over instances),
//! laid out flat for glsl/trace/compute.glsl. Triangles are not copied: the
//! shader reads them from the one shared vertex/index buffer.

use anyhow::Result;
use ash::vk;
use glam::Mat4;

use gpu_allocator::MemoryLocation;

use super::bvh::{triangle_aabbs, Bvh, BvhNode};
use super::compute_refit::ComputeRefit;
use super::dynamic::{RebuildPolicy, RefitState, Update};
use super::{instance_mask, instance_opaque};
use crate::gpu::scene::GpuScene;
use crate::scene::{Aabb, Instance, Scene};
use crate::vk::pipeline::{Binding, DescriptorSet};
use crate::vk::{Buffer, Context};

/// Mirrors `BvhInstance` in glsl/trace/compute.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBvhInstance {
    pub world_to_object: [f32; 16],
    pub node_offset: u32,
    pub prim_offset: u32,
    pub mask: u32,
    pub opaque: u32,
}
const _: () = assert!(std::mem::size_of::<GpuBvhInstance>() == 80);

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
    blas_nodes: Buffer,
    blas_prims: Buffer,
    tlas_nodes: Buffer,
    tlas_prims: Buffer,
    instances: Buffer,
    pub set: DescriptorSet,
    pub build_ms: f64,
    pub triangles: usize,
}

fn append(nodes: &mut Vec<BvhNode>, prims: &mut Vec<u32>, bvh: Bvh, capacity: usize) -> BlasRef {
    let r = BlasRef { node_offset: nodes.len() as u32, prim_offset: prims.len() as u32, bvh };
    nodes.extend_from_slice(&r.bvh.nodes);
    nodes.resize(r.node_offset as usize + capacity.max(r.bvh.nodes.len()), EMPTY_NODE);
    prims.extend_from_slice(&r.bvh.prim_indices);
    r
}

/// Top-level buffers are host-visible and rewritten in place every frame
/// something moves; sized for the worst case once.
fn host_buffer(ctx: &Context, name: &str, bytes: usize) -> Result<Buffer> {
    Buffer::new(ctx, name, bytes as u64, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryLocation::CpuToGpu)
}

impl ComputeBvh {
    pub fn build(ctx: &Context, scene: &Scene, gpu: &GpuScene) -> Result<ComputeBvh> {
        let t0 = std::time::Instant::now();
        let mut nodes: Vec<BvhNode> = Vec::new();
        let mut prims: Vec<u32> = Vec::new();
        let mut triangles = 0;
        // Primitives drawn only skinned (or not at all) get no static tree.
        let used = scene.rigidly_instanced();
        let blas: Vec<Vec<Option<BlasRef>>> = scene
            .meshes
            .iter()
            .zip(&used)
            .map(|(mesh, used)| {
                mesh.primitives
                    .iter()
                    .zip(used)
                    .map(|(p, used)| {
                        if p.indices.len() < 3 || !used {
                            return None;
                        }
                        triangles += p.indices.len() / 3;
                        let bvh = Bvh::build(&triangle_aabbs(&p.vertices, &p.indices));
                        Some(append(&mut nodes, &mut prims, bvh, 0))
                    })
                    .collect()
            })
            .collect();
        // Skinned instances: their own trees over the current (CPU) pose,
        // which is exactly what the GPU vertex range holds at upload.
        let world = scene.world_matrices();
        let mut skinned = Vec::new();
        for inst in &scene.instances {
            let Some(posed) = scene.skinned_pose(inst, &world) else { continue };
            let indices = &scene.meshes[inst.mesh].primitives[inst.primitive].indices;
            triangles += indices.len() / 3;
            let aabbs = triangle_aabbs(&posed, indices);
            let bvh = Bvh::build(&aabbs);
            let state = RefitState::new(&bvh.root_bounds());
            let blas = append(&mut nodes, &mut prims, bvh, (2 * aabbs.len()).saturating_sub(1));
            skinned.push(SkinnedBvh { blas, state });
        }
        let blas_ms = t0.elapsed().as_secs_f64() * 1e3;
        if nodes.is_empty() {
            nodes.push(EMPTY_NODE);
            prims.push(0);
        }
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let blas_nodes = Buffer::with_data(ctx, "BVH BLAS nodes", bytemuck::cast_slice(&nodes), storage)?;
        let blas_prims =
            Buffer::with_data(ctx, "BVH BLAS triangle order", bytemuck::cast_slice(&prims), storage)?;
        let refit = if skinned.is_empty() {
            None
        } else {
            let refs: Vec<_> =
                skinned.iter().map(|s| (&s.blas.bvh, s.blas.node_offset, s.blas.prim_offset)).collect();
            Some(ComputeRefit::new(ctx, gpu, &refs, &blas_nodes, &blas_prims)?)
        };

        let n = scene.instances.len().max(1);
        let tlas_nodes = host_buffer(ctx, "BVH top-level nodes", 2 * n * std::mem::size_of::<BvhNode>())?;
        let tlas_prims = host_buffer(ctx, "BVH top-level instance order", 4 * n)?;
        let instances = host_buffer(ctx, "BVH instances", n * std::mem::size_of::<GpuBvhInstance>())?;
        let sb = Binding::one(vk::DescriptorType::STORAGE_BUFFER);
        let set = DescriptorSet::new(ctx, "trace set (compute BVH)", &[sb, sb, sb, sb, sb])?;
        for (i, b) in [&blas_nodes, &blas_prims, &tlas_nodes, &tlas_prims, &instances].iter().enumerate() {
            set.write_buffer(ctx, i as u32, b.raw);
        }
        let mut bvh = ComputeBvh {
            blas,
            skinned,
            refit,
            blas_nodes,
            blas_prims,
            tlas_nodes,
            tlas_prims,
            instances,
            set,
            build_ms: 0.0,
            triangles,
        };
        // Fit the skinned trees to the GPU's vertices (the CPU pose they were
        // built from may differ in the last bit), which also places the top level.
        let updates = vec![Update::Refit; bvh.skinned.len()];
        ctx.one_shot("refit skinned BVHs", |cmd| {
            bvh.record_refit(ctx, cmd);
            Ok(())
        })?;
        bvh.finish_refit(scene, &updates, &RebuildPolicy::default())?;
        bvh.build_ms = t0.elapsed().as_secs_f64() * 1e3;
        log::info!(
            "compute BVH: {} triangles in {} nodes, built in {:.0} ms ({:.2} Mtri/s), triangle-weighted SAH cost {:.1}, top level over {} instances, {} refit each frame",
            triangles,
            nodes.len(),
            blas_ms,
            triangles as f64 / (blas_ms.max(1e-3) * 1e3),
            bvh.mean_sah_cost(),
            scene.instances.len(),
            bvh.skinned.len()
        );
        Ok(bvh)
    }

    /// Rebuilds the small top level (and the per-instance records) after
    /// instances moved or skinned trees were refit. The caller ensures the
    /// GPU is not reading the old contents.
    pub fn update_instances(&mut self, scene: &Scene) -> Result<()> {
        let (tlas, instances) = top_level(scene, |inst| match inst.skinned {
            Some(slot) => self.skinned.get(slot).map(|s| &s.blas),
            None => self.blas[inst.mesh][inst.primitive].as_ref(),
        });
        self.tlas_nodes.write(0, bytemuck::cast_slice(&tlas.nodes))?;
        self.tlas_prims.write(0, bytemuck::cast_slice(&tlas.prim_indices))?;
        self.instances.write(0, bytemuck::cast_slice(&instances))
    }

    /// Number of skinned trees (refit every frame).
    pub fn skinned_count(&self) -> usize {
        self.skinned.len()
    }

    /// Before recording a frame's update: rebuilds (on the CPU, from the
    /// scene's CPU pose) the skinned trees the policy marks, uploading their
    /// topology; the GPU refit recorded next then fits them to the GPU's
    /// skinned vertices. Returns what each slot gets this frame.
    pub fn prepare_skinned(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        policy: &RebuildPolicy,
    ) -> Result<Vec<Update>> {
        let updates: Vec<Update> = self.skinned.iter().map(|s| s.state.next(policy)).collect();
        if !updates.contains(&Update::Rebuild) {
            return Ok(updates);
        }
        let world = scene.world_matrices();
        let mut trees = Vec::new();
        for (inst, _) in scene
            .instances
            .iter()
            .filter_map(|i| Some((i, i.skinned?)))
            .filter(|(_, s)| updates[*s] == Update::Rebuild)
        {
            let slot = inst.skinned.unwrap();
            let posed = scene.skinned_pose(inst, &world).expect("skinned slot has a pose");
            let indices = &scene.meshes[inst.mesh].primitives[inst.primitive].indices;
            let bvh = Bvh::build(&triangle_aabbs(&posed, indices));
            let b = &mut self.skinned[slot].blas;
            self.blas_nodes.upload(ctx, b.node_offset as u64 * 32, bytemuck::cast_slice(&bvh.nodes))?;
            self.blas_prims.upload(ctx, b.prim_offset as u64 * 4, bytemuck::cast_slice(&bvh.prim_indices))?;
            b.bvh = bvh;
            trees.push(slot);
        }
        if let Some(refit) = &mut self.refit {
            for slot in trees {
                refit.set_levels(slot, &self.skinned[slot].blas.bvh)?;
            }
        }
        Ok(updates)
    }

    /// Records the GPU refit of every skinned tree (after skinning).
    pub fn record_refit(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        if let Some(refit) = &self.refit {
            refit.record(ctx, cmd);
        }
    }

    /// After the refit completed: takes the refit roots, judges them for the
    /// rebuild policy and rebuilds the top level.
    pub fn finish_refit(&mut self, scene: &Scene, updates: &[Update], policy: &RebuildPolicy) -> Result<()> {
        if let Some(refit) = &self.refit {
            for ((s, root), u) in self.skinned.iter_mut().zip(refit.roots()?).zip(updates) {
                s.blas.bvh.nodes[0] = root;
                s.state.done(*u, &s.blas.bvh.root_bounds(), policy);
            }
        }
        self.update_instances(scene)
    }

    /// SAH cost of the per-primitive BVHs, averaged with triangle counts as weights.
    pub fn mean_sah_cost(&self) -> f32 {
        let (mut sum, mut weight) = (0.0f64, 0.0f64);
        for b in self.blas.iter().flatten().flatten() {
            let n = b.bvh.prim_indices.len() as f64;
            sum += b.bvh.sah_cost() as f64 * n;
            weight += n;
        }
        (sum / weight.max(1.0)) as f32
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for b in [
            &mut self.blas_nodes,
            &mut self.blas_prims,
            &mut self.tlas_nodes,
            &mut self.tlas_prims,
            &mut self.instances,
        ] {
            b.destroy(ctx);
        }
        if let Some(r) = &mut self.refit {
            r.destroy(ctx);
        }
        self.set.destroy(ctx);
    }
}

/// The top level over all instances (rebuilt whenever instances move) and
/// the per-instance records the shader needs.
fn top_level<'a>(
    scene: &Scene,
    blas_of: impl Fn(&Instance) -> Option<&'a BlasRef>,
) -> (Bvh, Vec<GpuBvhInstance>) {
    let mut records = Vec::with_capacity(scene.instances.len());
    // Only instances some ray can hit enter the top level; `traceable` maps
    // its primitive indices back to instance indices.
    let mut bounds = Vec::with_capacity(scene.instances.len());
    let mut traceable = Vec::with_capacity(scene.instances.len());
    for (i, inst) in scene.instances.iter().enumerate() {
        let b = blas_of(inst);
        let world_to_object = if inst.world.determinant().abs() > f32::MIN_POSITIVE {
            inst.world.inverse()
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
        });
        if let Some(n) = b.and_then(|b| b.bvh.nodes.first()).filter(|_| mask != 0) {
            let world = Aabb { min: n.min.into(), max: n.max.into() }.transformed(&inst.world);
            if world.min.is_finite() && world.max.is_finite() {
                bounds.push(world);
                traceable.push(i as u32);
            }
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
