//! Updatable BLASes for skinned instances: built once (ALLOW_UPDATE + PREFER_FAST_BUILD), refit in
//! place after skinning every frame, rebuilt when the policy says refits degraded them. Each has its
//! own scratch region so a frame's builds go in one command.

use anyhow::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{blas_sizes, triangles, AccelStruct};
use crate::gpu::scene::{GpuScene, PrimitiveRange};
use crate::scene::Aabb;
use crate::vk::{built, Buffer, Context};

/// When a refit BLAS is rebuilt: after `max_refits` refits in a row (None: no limit; Some(0): every
/// frame), or when the deformed bounds' area exceeds `area_growth` times its last build's (a tree
/// built for another pose overlaps more as the mesh spreads out).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RebuildPolicy {
    pub max_refits: Option<u32>,
    pub area_growth: f32,
}

impl Default for RebuildPolicy {
    fn default() -> Self {
        Self { max_refits: None, area_growth: 1.5 }
    }
}

impl RebuildPolicy {
    /// Refit forever (for measuring what refitting alone costs and does).
    pub const NEVER: RebuildPolicy = RebuildPolicy { max_refits: None, area_growth: f32::INFINITY };
    /// Rebuild every frame (the reference a refit is compared with).
    pub const ALWAYS: RebuildPolicy = RebuildPolicy { max_refits: Some(0), area_growth: f32::INFINITY };
}

/// What happened to one dynamic structure this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Update {
    Refit,
    Rebuild,
}

/// Per-structure bookkeeping of the policy (shared with the compute BVH).
#[derive(Clone, Copy, Debug)]
pub struct RefitState {
    pub refits: u32,
    /// Surface area of the deformed bounds when last built.
    pub built_area: f32,
    /// Set from the bounds measured after a frame: rebuild next frame.
    pub degraded: bool,
}

impl RefitState {
    pub fn new(bounds: &Aabb) -> Self {
        Self { refits: 0, built_area: area(bounds), degraded: false }
    }

    /// The action for this frame.
    pub fn next(&self, policy: &RebuildPolicy) -> Update {
        let too_many = policy.max_refits.is_some_and(|m| self.refits >= m);
        if self.degraded || too_many {
            Update::Rebuild
        } else {
            Update::Refit
        }
    }

    /// Records what was done and judges the bounds it produced.
    pub fn done(&mut self, update: Update, bounds: &Aabb, policy: &RebuildPolicy) {
        let a = area(bounds);
        match update {
            Update::Rebuild => *self = RefitState::new(bounds),
            Update::Refit => {
                self.refits += 1;
                self.degraded = a > self.built_area * policy.area_growth;
            }
        }
    }
}

pub fn area(b: &Aabb) -> f32 {
    let e = b.extent();
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

pub struct DynamicBlas {
    pub accel: AccelStruct,
    range: PrimitiveRange,
    scratch_offset: u64,
    pub state: RefitState,
}

pub struct DynamicBlases {
    pub blases: Vec<DynamicBlas>,
    scratch: Option<Buffer>,
    scratch_address: u64,
}

impl DynamicBlases {
    /// The structures' and the shared scratch buffer's bytes.
    pub fn bytes(&self) -> u64 {
        self.blases.iter().map(|b| b.accel.buffer.size).sum::<u64>()
            + self.scratch.as_ref().map_or(0, |s| s.size)
    }
}

const FLAGS: vk::BuildAccelerationStructureFlagsKHR = vk::BuildAccelerationStructureFlagsKHR::from_raw(
    vk::BuildAccelerationStructureFlagsKHR::ALLOW_UPDATE.as_raw()
        | vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_BUILD.as_raw(),
);

impl DynamicBlases {
    /// Creates and builds one BLAS per skinned slot (`gpu.skinned`), whose
    /// vertices must already hold a pose.
    pub fn new(ctx: &Context, gpu: &GpuScene, bounds: &[Aabb], align: u64) -> Result<DynamicBlases> {
        // Objects land in `d` as they are made: an error destroys them.
        let d = DynamicBlases { blases: Vec::new(), scratch: None, scratch_address: 0 };
        built(ctx, d, |d| d.create(ctx, gpu, bounds, align))
    }

    fn create(&mut self, ctx: &Context, gpu: &GpuScene, bounds: &[Aabb], align: u64) -> Result<()> {
        let mut scratch_size = 0u64;
        for (slot, r) in gpu.skinned.iter().enumerate() {
            let sizes = blas_sizes(ctx, gpu, r, FLAGS);
            let accel = AccelStruct::new(
                ctx,
                &format!("BLAS skinned slot {slot} (refit)"),
                vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                sizes.acceleration_structure_size,
            )?;
            let need = sizes.build_scratch_size.max(sizes.update_scratch_size);
            self.blases.push(DynamicBlas {
                accel,
                range: *r,
                scratch_offset: scratch_size,
                state: RefitState::new(&bounds[slot]),
            });
            scratch_size += need.div_ceil(align) * align;
        }
        let scratch = Buffer::new(
            ctx,
            "skinned BLAS scratch",
            scratch_size + align,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            MemoryLocation::GpuOnly,
        )?;
        self.scratch_address = scratch.address.div_ceil(align) * align;
        self.scratch = Some(scratch);
        let all = vec![Update::Rebuild; self.blases.len()];
        ctx.one_shot("build skinned BLASes", |cmd| {
            self.record(ctx, cmd, gpu, &all);
            Ok(())
        })
    }

    /// Records this frame's refits / rebuilds (one entry per slot) in one
    /// command; the caller puts a barrier before the TLAS build.
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, gpu: &GpuScene, updates: &[Update]) {
        let loader = ctx.accel.as_ref().expect("acceleration structures enabled");
        let geoms: Vec<[vk::AccelerationStructureGeometryKHR; 1]> =
            self.blases.iter().map(|b| [triangles(gpu, &b.range)]).collect();
        let infos: Vec<_> = self
            .blases
            .iter()
            .zip(&geoms)
            .zip(updates)
            .map(|((b, g), u)| {
                let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
                    .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                    .flags(FLAGS)
                    .dst_acceleration_structure(b.accel.raw)
                    .geometries(g)
                    .scratch_data(vk::DeviceOrHostAddressKHR {
                        device_address: self.scratch_address + b.scratch_offset,
                    });
                match u {
                    // In place: source and destination are the same object.
                    Update::Refit => info
                        .mode(vk::BuildAccelerationStructureModeKHR::UPDATE)
                        .src_acceleration_structure(b.accel.raw),
                    Update::Rebuild => info.mode(vk::BuildAccelerationStructureModeKHR::BUILD),
                }
            })
            .collect();
        let ranges: Vec<[vk::AccelerationStructureBuildRangeInfoKHR; 1]> = self
            .blases
            .iter()
            .map(|b| {
                [vk::AccelerationStructureBuildRangeInfoKHR::default()
                    .primitive_count(b.range.index_count / 3)]
            })
            .collect();
        let range_refs: Vec<&[vk::AccelerationStructureBuildRangeInfoKHR]> =
            ranges.iter().map(|r| r.as_slice()).collect();
        if !infos.is_empty() {
            unsafe { loader.cmd_build_acceleration_structures(cmd, &infos, &range_refs) };
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for b in &mut self.blases {
            b.accel.destroy(ctx);
        }
        if let Some(mut s) = self.scratch.take() {
            s.destroy(ctx);
        }
    }
}

crate::destroy_by_method!(DynamicBlases);

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cube(half: f32) -> Aabb {
        Aabb { min: Vec3::splat(-half), max: Vec3::splat(half) }
    }

    #[test]
    fn policy_rebuilds_after_growth_or_too_many_refits() {
        let policy = RebuildPolicy { max_refits: Some(3), area_growth: 1.5 };
        let mut s = RefitState::new(&cube(1.0));
        assert_eq!(s.next(&policy), Update::Refit);
        s.done(Update::Refit, &cube(1.1), &policy); // area x1.21
        assert_eq!(s.next(&policy), Update::Refit);
        s.done(Update::Refit, &cube(1.3), &policy); // area x1.69 > 1.5
        assert_eq!(s.next(&policy), Update::Rebuild);
        s.done(Update::Rebuild, &cube(1.3), &policy);
        assert_eq!(s.next(&policy), Update::Refit);
        for _ in 0..3 {
            s.done(Update::Refit, &cube(1.3), &policy);
        }
        assert_eq!(s.next(&policy), Update::Rebuild, "max_refits reached");
        let never = RebuildPolicy::NEVER;
        let mut s = RefitState::new(&cube(1.0));
        for _ in 0..1000 {
            s.done(Update::Refit, &cube(100.0), &never);
        }
        assert_eq!(s.next(&never), Update::Refit);
        assert_eq!(RefitState::new(&cube(1.0)).next(&RebuildPolicy::ALWAYS), Update::Rebuild);
    }
}
