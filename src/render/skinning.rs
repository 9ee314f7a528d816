//! The skinning pass (glsl/anim/skinning.comp): once per frame every skinned instance's bind-pose
//! vertices are blended by its joint matrices into its range of the shared vertex buffer, read by the
//! G-buffer pass, the acceleration-structure refits and the compute tracer. It also measures each
//! instance's deformed bounds for the BLAS rebuild policy.

use anyhow::Result;
use ash::vk;
use glam::{Mat4, Vec3};
use gpu_allocator::MemoryLocation;

use crate::gpu::origin::RenderOrigin;
use crate::gpu::scene::GpuScene;
use crate::gpu::shared::{SKIN_BOUNDS, SKIN_DEST, SKIN_JOINTS, SKIN_SOURCE};
use crate::scene::{Aabb, Scene, Vertex};
use crate::vk::frame_ring::{Source, Uploads};
use crate::vk::pipeline::{bind_compute, compute_pipeline, pipeline_layout, DescriptorSet, Specialization};
use crate::vk::{built, Buffer, Context};

/// Mirrors `SkinVertex` in glsl/anim/skinning.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct SkinVertex {
    vertex: Vertex,
    joints: [u32; 4],
    weights: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<SkinVertex>() == 80);

/// Push constants of one dispatch (one skinned instance).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Job {
    src_offset: u32,
    dst_offset: u32,
    vertex_count: u32,
    joint_offset: u32,
    slot: u32,
}

pub struct Skinning {
    jobs: Vec<Job>,
    /// Per slot: (node, skin) whose joint matrices feed it.
    sources: Vec<(usize, usize)>,
    source: Buffer,
    joints: Buffer,
    bounds: Buffer,
    set: DescriptorSet,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

/// Encodes a float so that unsigned order is float order (as the shader does).
fn orderable(f: f32) -> u32 {
    let u = f.to_bits();
    if u & 0x8000_0000 != 0 {
        !u
    } else {
        u | 0x8000_0000
    }
}

fn from_orderable(u: u32) -> f32 {
    f32::from_bits(if u & 0x8000_0000 != 0 { u & 0x7fff_ffff } else { !u })
}

impl Skinning {
    /// None when the scene has no skinned instance.
    pub fn new(ctx: &Context, scene: &Scene, gpu: &GpuScene) -> Result<Option<Skinning>> {
        let skinned: Vec<_> = scene.instances.iter().filter(|i| i.skinned.is_some()).collect();
        if skinned.is_empty() {
            return Ok(None);
        }
        // Bind-pose data once per skinned primitive, shared by its instances.
        let mut source_data: Vec<SkinVertex> = Vec::new();
        let mut source_of: Vec<((usize, usize), u32)> = Vec::new();
        let (mut jobs, mut sources, mut joint_count) = (Vec::new(), Vec::new(), 0u32);
        for inst in skinned {
            let slot = inst.skinned.unwrap();
            let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
            let (Some(w), Some(skin)) = (&prim.skin, scene.nodes[inst.node].skin) else { continue };
            let key = (inst.mesh, inst.primitive);
            let src_offset = match source_of.iter().find(|(k, _)| *k == key) {
                Some((_, o)) => *o,
                None => {
                    let o = source_data.len() as u32;
                    source_data.extend(
                        prim.vertices
                            .iter()
                            .zip(w.joints.iter().zip(&w.weights))
                            .map(|(v, (j, w))| SkinVertex { vertex: *v, joints: *j, weights: *w }),
                    );
                    source_of.push((key, o));
                    o
                }
            };
            let r = gpu.skinned[slot];
            jobs.push(Job {
                src_offset,
                dst_offset: r.vertex_offset,
                vertex_count: r.vertex_count,
                joint_offset: joint_count,
                slot: slot as u32,
            });
            sources.push((inst.node, skin));
            joint_count += scene.skins[skin].joints.len() as u32;
        }
        // GPU objects land in `sk` as they are made: an error destroys them.
        let sk = Skinning {
            jobs,
            sources,
            source: Buffer::null(),
            joints: Buffer::null(),
            bounds: Buffer::null(),
            set: DescriptorSet::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        };
        let sk = built(ctx, sk, |sk| sk.create(ctx, gpu, &source_data, joint_count))?;
        log::info!(
            "skinning: {} skinned instances, {} bind-pose vertices, {} joints",
            sk.jobs.len(),
            source_data.len(),
            joint_count
        );
        Ok(Some(sk))
    }

    fn create(
        &mut self,
        ctx: &Context,
        gpu: &GpuScene,
        source_data: &[SkinVertex],
        joint_count: u32,
    ) -> Result<()> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        self.source =
            Buffer::with_data(ctx, "skinning bind pose", bytemuck::cast_slice(source_data), storage)?;
        self.joints = Buffer::new(
            ctx,
            "skinning joint matrices",
            joint_count as u64 * 64,
            storage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let bounds_size = self.jobs.len() as u64 * 24;
        let transfer = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        self.bounds =
            Buffer::new(ctx, "skinned bounds", bounds_size, storage | transfer, MemoryLocation::GpuOnly)?;
        self.set = DescriptorSet::storage_buffers(
            ctx,
            "skinning set",
            &[
                (SKIN_SOURCE, self.source.raw),
                (SKIN_JOINTS, self.joints.raw),
                (SKIN_DEST, gpu.vertices.raw),
                (SKIN_BOUNDS, self.bounds.raw),
            ],
        )?;
        self.layout =
            pipeline_layout(ctx, "skinning layout", &[self.set.layout], std::mem::size_of::<Job>() as u32)?;
        self.pipeline = compute_pipeline(ctx, "anim/skinning.comp", self.layout, &Specialization::new(&[]))?;
        Ok(())
    }

    /// Writes this frame's joint matrices and resets the bounds accumulators (via the frame's ring slot).
    pub fn write(&self, up: &mut Uploads, scene: &Scene, origin: RenderOrigin) -> Result<()> {
        // Node matrices relative to the render origin (joint matrices are
        // relative products, combined in f64 either way).
        let world: Vec<_> = scene.world_matrices().iter().map(|m| origin.relative(m)).collect();
        let mut m: Vec<Mat4> = Vec::new();
        for &(node, skin) in &self.sources {
            m.extend(scene.joint_matrices(skin, node, &world));
        }
        up.write(&self.joints, 0, bytemuck::cast_slice(&m))?;
        let (lo, hi) = (orderable(f32::INFINITY), orderable(f32::NEG_INFINITY));
        let reset: Vec<u32> = (0..self.jobs.len()).flat_map(|_| [lo, lo, lo, hi, hi, hi]).collect();
        up.write(&self.bounds, 0, bytemuck::cast_slice(&reset))
    }

    /// Records the dispatches. The pass layer orders the vertex writes before their readers (declared
    /// `Geometry` uses); the ring's download at the frame's end waits for the bounds (`bounds_source`).
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        let d = &ctx.device;
        unsafe {
            bind_compute(ctx, cmd, self.pipeline, self.layout, &[self.set.set]);
            for job in &self.jobs {
                d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::ALL, 0, bytemuck::bytes_of(job));
                d.cmd_dispatch(cmd, job.vertex_count.div_ceil(64), 1, 1);
            }
        }
    }

    /// Where the ring's download reads the deformed bounds from.
    pub fn bounds_source(&self) -> Source {
        Source::Buffer { buffer: self.bounds.raw, offset: 0, size: self.bounds.size }
    }

    /// Deformed bounds of each slot, from the bytes of `bounds_source` of a completed frame.
    pub fn bounds(&self, bytes: &[u8]) -> Result<Vec<Aabb>> {
        let raw: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes[..self.jobs.len() * 24]);
        Ok(raw
            .chunks_exact(6)
            .map(|b| Aabb {
                min: Vec3::new(from_orderable(b[0]), from_orderable(b[1]), from_orderable(b[2])),
                max: Vec3::new(from_orderable(b[3]), from_orderable(b[4]), from_orderable(b[5])),
            })
            .collect())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_pipeline(self.pipeline, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        self.set.destroy(ctx);
        for b in [&mut self.source, &mut self.joints, &mut self.bounds] {
            b.destroy(ctx);
        }
    }
}

crate::destroy_by_method!(Skinning);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orderable_floats_sort_like_floats() {
        let v = [-1e30f32, -2.5, -0.0, 0.0, 1e-30, 3.0, 1e30];
        for w in v.windows(2) {
            assert!(orderable(w[0]) <= orderable(w[1]), "{} vs {}", w[0], w[1]);
        }
        for f in v {
            assert_eq!(from_orderable(orderable(f)).to_bits(), f.to_bits());
        }
    }
}
