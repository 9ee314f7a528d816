//! The compute backend's acceleration structure: our own two-level BVH
//! (one binned-SAH BVH per mesh primitive + a top level over instances),
//! laid out flat for glsl/trace/compute.glsl. Triangles are not copied: the
//! shader reads them from the one shared vertex/index buffer.

use anyhow::Result;
use ash::vk;
use glam::Mat4;

use super::bvh::{triangle_aabbs, Bvh, BvhNode};
use super::{instance_mask, instance_opaque};
use crate::render::gpu_scene::GpuScene;
use crate::scene::{Aabb, Scene};
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

pub struct ComputeBvh {
    /// Per mesh, per primitive (None for empty primitives).
    blas: Vec<Vec<Option<BlasRef>>>,
    blas_nodes: Buffer,
    blas_prims: Buffer,
    tlas_nodes: Buffer,
    tlas_prims: Buffer,
    instances: Buffer,
    pub set: DescriptorSet,
    pub build_ms: f64,
    pub triangles: usize,
}

impl ComputeBvh {
    pub fn build(ctx: &Context, scene: &Scene, _gpu: &GpuScene) -> Result<ComputeBvh> {
        let t0 = std::time::Instant::now();
        let mut nodes: Vec<BvhNode> = Vec::new();
        let mut prims: Vec<u32> = Vec::new();
        let mut triangles = 0;
        let blas: Vec<Vec<Option<BlasRef>>> = scene
            .meshes
            .iter()
            .map(|mesh| {
                mesh.primitives
                    .iter()
                    .map(|p| {
                        if p.indices.len() < 3 {
                            return None;
                        }
                        triangles += p.indices.len() / 3;
                        let bvh = Bvh::build(&triangle_aabbs(&p.vertices, &p.indices));
                        let r =
                            BlasRef { node_offset: nodes.len() as u32, prim_offset: prims.len() as u32, bvh };
                        nodes.extend_from_slice(&r.bvh.nodes);
                        prims.extend_from_slice(&r.bvh.prim_indices);
                        Some(r)
                    })
                    .collect()
            })
            .collect();
        let blas_ms = t0.elapsed().as_secs_f64() * 1e3;
        if nodes.is_empty() {
            nodes.push(EMPTY_NODE);
            prims.push(0);
        }
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let blas_nodes = Buffer::with_data(ctx, "BVH BLAS nodes", bytemuck::cast_slice(&nodes), storage)?;
        let blas_prims =
            Buffer::with_data(ctx, "BVH BLAS triangle order", bytemuck::cast_slice(&prims), storage)?;

        let (tlas, instances) = top_level(scene, &blas);
        let tlas_nodes =
            Buffer::with_data(ctx, "BVH top-level nodes", bytemuck::cast_slice(&tlas.nodes), storage)?;
        let tlas_prims = Buffer::with_data(
            ctx,
            "BVH top-level instance order",
            bytemuck::cast_slice(&tlas.prim_indices),
            storage,
        )?;
        let instances = Buffer::with_data(ctx, "BVH instances", bytemuck::cast_slice(&instances), storage)?;

        let sb = Binding::one(vk::DescriptorType::STORAGE_BUFFER);
        let set = DescriptorSet::new(ctx, "trace set (compute BVH)", &[sb, sb, sb, sb, sb])?;
        for (i, b) in [&blas_nodes, &blas_prims, &tlas_nodes, &tlas_prims, &instances].iter().enumerate() {
            set.write_buffer(ctx, i as u32, b.raw);
        }
        let build_ms = t0.elapsed().as_secs_f64() * 1e3;
        let bvh = ComputeBvh {
            blas,
            blas_nodes,
            blas_prims,
            tlas_nodes,
            tlas_prims,
            instances,
            set,
            build_ms,
            triangles,
        };
        log::info!(
            "compute BVH: {} triangles in {} nodes, built in {:.0} ms ({:.2} Mtri/s), triangle-weighted SAH cost {:.1}, top level over {} instances",
            triangles,
            nodes.len(),
            blas_ms,
            triangles as f64 / (blas_ms.max(1e-3) * 1e3),
            bvh.mean_sah_cost(),
            scene.instances.len()
        );
        Ok(bvh)
    }

    /// Rebuilds the small top level (and the per-instance records) after
    /// instances moved; the per-primitive BVHs are untouched. The caller
    /// ensures the GPU is not reading the old buffers.
    pub fn update_instances(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let (tlas, instances) = top_level(scene, &self.blas);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        for b in [&mut self.tlas_nodes, &mut self.tlas_prims, &mut self.instances] {
            b.destroy(ctx);
        }
        self.tlas_nodes =
            Buffer::with_data(ctx, "BVH top-level nodes", bytemuck::cast_slice(&tlas.nodes), storage)?;
        self.tlas_prims = Buffer::with_data(
            ctx,
            "BVH top-level instance order",
            bytemuck::cast_slice(&tlas.prim_indices),
            storage,
        )?;
        self.instances = Buffer::with_data(ctx, "BVH instances", bytemuck::cast_slice(&instances), storage)?;
        self.set.write_buffer(ctx, 2, self.tlas_nodes.raw);
        self.set.write_buffer(ctx, 3, self.tlas_prims.raw);
        self.set.write_buffer(ctx, 4, self.instances.raw);
        Ok(())
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
        self.set.destroy(ctx);
    }
}

/// The top level over all instances (rebuilt whenever instances move) and
/// the per-instance records the shader needs.
fn top_level(scene: &Scene, blas: &[Vec<Option<BlasRef>>]) -> (Bvh, Vec<GpuBvhInstance>) {
    let mut records = Vec::with_capacity(scene.instances.len());
    // Only instances some ray can hit enter the top level; `traceable` maps
    // its primitive indices back to instance indices.
    let mut bounds = Vec::with_capacity(scene.instances.len());
    let mut traceable = Vec::with_capacity(scene.instances.len());
    for (i, inst) in scene.instances.iter().enumerate() {
        let b = blas[inst.mesh][inst.primitive].as_ref();
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
