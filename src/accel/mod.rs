//! Vulkan acceleration structures: one BLAS per mesh primitive, built from the single shared
//! vertex/index copy (PREFER_FAST_TRACE, compacted), and one TLAS over all instances. Sizes come from
//! the driver's queries.

use crate::gpu::origin::RenderOrigin;
use anyhow::{Context as _, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;

pub mod bvh;
pub mod compute_bvh;
pub mod compute_refit;
pub mod compute_top_level;
pub mod cpu_trace;
pub mod dynamic;
pub mod flat;
pub mod flat_cache;
pub mod lbvh;

use dynamic::{DynamicBlases, Update};

use crate::gpu::scene::{GpuScene, PrimitiveRange};
use crate::scene::{AlphaMode, Instance, Scene};
use crate::vk::frame_ring::{upload_now, Uploads};
use crate::vk::{memory_barrier, Buffer, Context};

/// TLAS instance mask bits: what kind of ray may hit an instance.
pub const MASK_VISIBLE: u8 = crate::gpu::shared::MASK_VISIBLE as u8;
pub const MASK_SHADOW: u8 = crate::gpu::shared::MASK_SHADOW as u8;

/// Whether every hit on `inst` is final (no alpha test, no transmission): such instances skip any-hit
/// processing in every backend.
pub fn instance_opaque(scene: &Scene, inst: &Instance) -> bool {
    let m = &scene.materials[scene.instance_material(inst)];
    m.alpha_mode == AlphaMode::Opaque && m.transmission <= 0.0
}

/// Which rays may hit `inst`: MASK_VISIBLE always, MASK_SHADOW when both the object and its material
/// cast shadows.
pub fn instance_mask(scene: &Scene, inst: &Instance) -> u8 {
    let m = &scene.materials[scene.instance_material(inst)];
    let casts = scene.objects.get(inst.object).is_none_or(|o| o.props.casts_shadows) && m.casts_shadows;
    MASK_VISIBLE | if casts { MASK_SHADOW } else { 0 }
}

pub struct AccelStruct {
    pub raw: vk::AccelerationStructureKHR,
    pub buffer: Buffer,
    pub address: vk::DeviceAddress,
}

impl AccelStruct {
    fn new(
        ctx: &Context,
        name: &str,
        ty: vk::AccelerationStructureTypeKHR,
        size: u64,
    ) -> Result<AccelStruct> {
        let loader = ctx.accel.as_ref().context("acceleration structures are not enabled")?;
        let buffer = Buffer::new(
            ctx,
            &format!("{name} storage"),
            size,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            MemoryLocation::GpuOnly,
        )?;
        let mut buffer = buffer;
        let created = unsafe {
            loader.create_acceleration_structure(
                &vk::AccelerationStructureCreateInfoKHR::default().buffer(buffer.raw).size(size).ty(ty),
                None,
            )
        };
        let raw = created.inspect_err(|_| buffer.destroy(ctx))?;
        ctx.name(raw, name);
        let address = unsafe {
            loader.get_acceleration_structure_device_address(
                &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw),
            )
        };
        Ok(AccelStruct { raw, buffer, address })
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if let Some(loader) = &ctx.accel {
            unsafe { loader.destroy_acceleration_structure(self.raw, None) };
        }
        self.buffer.destroy(ctx);
    }
}

fn scratch_alignment(ctx: &Context) -> u64 {
    let mut asp = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut asp);
    unsafe { ctx.instance.raw.get_physical_device_properties2(ctx.physical_device, &mut p2) };
    (asp.min_acceleration_structure_scratch_offset_alignment as u64).max(1)
}

/// A scratch buffer reused by every build; grows when a build needs more.
struct Scratch {
    buffer: Option<Buffer>,
    align: u64,
}

impl Scratch {
    fn address(&mut self, ctx: &Context, size: u64) -> Result<vk::DeviceAddress> {
        let need = size + self.align;
        if self.buffer.as_ref().is_none_or(|b| b.size < need) {
            if let Some(mut b) = self.buffer.take() {
                b.destroy(ctx);
            }
            self.buffer = Some(Buffer::new(
                ctx,
                "acceleration structure scratch",
                need,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
                MemoryLocation::GpuOnly,
            )?);
        }
        let a = self.buffer.as_ref().unwrap().address;
        Ok(a.div_ceil(self.align) * self.align)
    }

    fn destroy(&mut self, ctx: &Context) {
        if let Some(mut b) = self.buffer.take() {
            b.destroy(ctx);
        }
    }
}

pub(crate) fn triangles<'a>(gpu: &GpuScene, r: &PrimitiveRange) -> vk::AccelerationStructureGeometryKHR<'a> {
    let tri = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
        .vertex_format(vk::Format::R32G32B32_SFLOAT)
        .vertex_data(vk::DeviceOrHostAddressConstKHR {
            device_address: gpu.vertices.address + r.vertex_offset as u64 * 48,
        })
        .vertex_stride(48)
        .max_vertex(r.vertex_count.saturating_sub(1))
        .index_type(vk::IndexType::UINT32)
        .index_data(vk::DeviceOrHostAddressConstKHR {
            device_address: gpu.indices.address + r.first_index as u64 * 4,
        });
    // Opacity is decided per instance (FORCE_OPAQUE / FORCE_NO_OPAQUE): objects can override a shared
    // primitive's material. Shadow transmittance multiplies every crossing once: no duplicates.
    vk::AccelerationStructureGeometryKHR::default()
        .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
        .flags(vk::GeometryFlagsKHR::NO_DUPLICATE_ANY_HIT_INVOCATION)
        .geometry(vk::AccelerationStructureGeometryDataKHR { triangles: tri })
}

/// Driver-reported sizes of a BLAS over one primitive range.
pub(crate) fn blas_sizes(
    ctx: &Context,
    gpu: &GpuScene,
    r: &PrimitiveRange,
    flags: vk::BuildAccelerationStructureFlagsKHR,
) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
    let loader = ctx.accel.as_ref().expect("acceleration structures enabled");
    let geoms = [triangles(gpu, r)];
    let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
        .flags(flags)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(&geoms);
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    unsafe {
        loader.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            &info,
            &[r.index_count / 3],
            &mut sizes,
        )
    };
    sizes
}

/// All acceleration structures of a scene.
pub struct SceneAccel {
    /// Indexed by mesh, then primitive; None for empty primitives.
    pub blases: Vec<Vec<Option<AccelStruct>>>,
    pub tlas: AccelStruct,
    /// Updatable BLASes of skinned instances (by slot), if any.
    pub dynamic: Option<DynamicBlases>,
    instances: Buffer,
    scratch: Scratch,
    pub build_ms: f64,
    /// The GPU scene's render origin (instance transforms are relative to it).
    origin: RenderOrigin,
}

impl SceneAccel {
    pub fn build(ctx: &Context, scene: &Scene, gpu: &GpuScene) -> Result<SceneAccel> {
        crate::progress::stage("building the acceleration structures");
        // Everything created lands in `accel` at once, so an error half-way destroys what exists.
        let accel = SceneAccel {
            tlas: AccelStruct {
                raw: vk::AccelerationStructureKHR::null(),
                buffer: Buffer::null(),
                address: 0,
            },
            blases: Vec::new(),
            dynamic: None,
            instances: Buffer::null(),
            scratch: Scratch { buffer: None, align: scratch_alignment(ctx) },
            build_ms: 0.0,
            origin: gpu.origin,
        };
        crate::vk::built(ctx, accel, |a| a.fill(ctx, scene, gpu))
    }

    fn fill(&mut self, ctx: &Context, scene: &Scene, gpu: &GpuScene) -> Result<()> {
        let t0 = std::time::Instant::now();
        let loader = ctx.accel.as_ref().context("acceleration structures are not enabled")?;

        // 1. Size and create every BLAS.
        let flags = vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE
            | vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION;
        let blases = &mut self.blases;
        let mut jobs = Vec::new(); // (mesh, prim, scratch size)
                                   // Primitives drawn only skinned (or not at all) get no static BLAS.
        let used = scene.rigidly_instanced();
        for (m, prims) in gpu.ranges.iter().enumerate() {
            // In place from the start: a failure destroys what exists.
            blases.push(Vec::new());
            let row = blases.last_mut().expect("pushed");
            for (p, r) in prims.iter().enumerate() {
                if r.index_count < 3 || !used[m][p] {
                    row.push(None);
                    continue;
                }
                let sizes = blas_sizes(ctx, gpu, r, flags);
                let name = format!("BLAS '{}' #{p}", scene.meshes[m].name);
                let level = vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL;
                row.push(Some(AccelStruct::new(ctx, &name, level, sizes.acceleration_structure_size)?));
                jobs.push((m, p, sizes.build_scratch_size));
            }
        }

        // 2. Build them one after another through one scratch buffer, then query compacted sizes.
        let max_scratch = jobs.iter().map(|j| j.2).max().unwrap_or(0);
        let scratch_addr = self.scratch.address(ctx, max_scratch)?;
        let blases = &mut self.blases;
        let query_pool = unsafe {
            ctx.device.create_query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
                    .query_count(jobs.len().max(1) as u32),
                None,
            )?
        };
        let build_barrier = (
            vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
            vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR
                | vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
        );
        let built = ctx.one_shot("build BLASes", |cmd| {
            unsafe { ctx.device.cmd_reset_query_pool(cmd, query_pool, 0, jobs.len().max(1) as u32) };
            for (m, p, _) in &jobs {
                let r = &gpu.ranges[*m][*p];
                let geoms = [triangles(gpu, r)];
                let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
                    .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                    .flags(flags)
                    .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
                    .dst_acceleration_structure(blases[*m][*p].as_ref().unwrap().raw)
                    .geometries(&geoms)
                    .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch_addr });
                let range =
                    [vk::AccelerationStructureBuildRangeInfoKHR::default()
                        .primitive_count(r.index_count / 3)];
                unsafe { loader.cmd_build_acceleration_structures(cmd, &[info], &[&range]) };
                memory_barrier(ctx, cmd, build_barrier, build_barrier);
            }
            let all: Vec<_> = jobs.iter().map(|(m, p, _)| blases[*m][*p].as_ref().unwrap().raw).collect();
            if !all.is_empty() {
                unsafe {
                    loader.cmd_write_acceleration_structures_properties(
                        cmd,
                        &all,
                        vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                        query_pool,
                        0,
                    )
                };
            }
            Ok(())
        });

        // 3. Compact: copy each BLAS into a buffer of its compacted size.
        let mut compacted = vec![0u64; jobs.len()];
        let queried = built.and_then(|()| {
            if !jobs.is_empty() {
                unsafe {
                    ctx.device.get_query_pool_results(
                        query_pool,
                        0,
                        &mut compacted,
                        vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                    )?
                };
            }
            Ok(())
        });
        unsafe { ctx.device.destroy_query_pool(query_pool, None) };
        queried?;
        let (mut before, mut after) = (0u64, 0u64);
        // The uncompacted BLASes; destroyed whether compaction works or not.
        let mut olds = Vec::new();
        let compaction = (|| {
            for ((m, p, _), size) in jobs.iter().zip(&compacted) {
                let name = format!("BLAS '{}' #{p} (compacted)", scene.meshes[*m].name);
                let new = AccelStruct::new(
                    ctx,
                    &name,
                    vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                    (*size).max(256),
                )?;
                let old = blases[*m][*p].replace(new).unwrap();
                before += old.buffer.size;
                after += blases[*m][*p].as_ref().unwrap().buffer.size;
                olds.push((old, (*m, *p)));
            }
            if olds.is_empty() {
                return Ok(());
            }
            ctx.one_shot("compact BLASes", |cmd| {
                for (old, (m, p)) in &olds {
                    let info = vk::CopyAccelerationStructureInfoKHR::default()
                        .src(old.raw)
                        .dst(blases[*m][*p].as_ref().unwrap().raw)
                        .mode(vk::CopyAccelerationStructureModeKHR::COMPACT);
                    unsafe { loader.cmd_copy_acceleration_structure(cmd, &info) };
                }
                Ok(())
            })
        })();
        for (mut old, _) in olds {
            old.destroy(ctx);
        }
        compaction?;

        // 4. TLAS over all instances.
        self.instances = Buffer::new(
            ctx,
            "TLAS instances",
            (scene.instances.len().max(1) * std::mem::size_of::<vk::AccelerationStructureInstanceKHR>())
                as u64,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
                | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        if !gpu.skinned.is_empty() {
            self.dynamic = Some(DynamicBlases::new(ctx, gpu, &gpu.skinned_bounds, self.scratch.align)?);
        }
        self.build_tlas(ctx, scene)?;
        self.build_ms = t0.elapsed().as_secs_f64() * 1e3;
        log::info!(
            "acceleration structures: {} BLASes ({:.1} MiB -> {:.1} MiB compacted), TLAS over {} instances, {:.0} ms",
            jobs.len(),
            before as f64 / 1048576.0,
            after as f64 / 1048576.0,
            scene.instances.len(),
            self.build_ms
        );
        Ok(())
    }

    /// Bytes of every structure's buffer, the instance records and the scratch kept for updates.
    pub fn bytes(&self) -> u64 {
        let blases: u64 = self.blases.iter().flatten().flatten().map(|b| b.buffer.size).sum();
        let scratch = self.scratch.buffer.as_ref().map_or(0, |b| b.size);
        let dynamic = self.dynamic.as_ref().map_or(0, |d| d.bytes());
        blases + self.tlas.buffer.size + self.instances.size + scratch + dynamic
    }

    /// Writes the instance records and (re)builds the TLAS, waiting for it.
    pub fn build_tlas(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        upload_now(ctx, "TLAS instances", |up| self.write_instances(up, scene))?;
        ctx.one_shot("build TLAS", |cmd| {
            // The upload's copy (an earlier submission) before the build reads it.
            memory_barrier(
                ctx,
                cmd,
                (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
                (vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR, vk::AccessFlags2::SHADER_READ),
            );
            self.record_tlas(ctx, cmd, scene)
        })
    }

    /// Records the refit / rebuild of every skinned BLAS (one entry per slot), then the barrier the TLAS
    /// build needs.
    pub fn record_dynamic(&self, ctx: &Context, cmd: vk::CommandBuffer, gpu: &GpuScene, updates: &[Update]) {
        let Some(d) = &self.dynamic else { return };
        d.record(ctx, cmd, gpu, updates);
        let build = vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR;
        memory_barrier(
            ctx,
            cmd,
            (build, vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR),
            (build, vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR),
        );
    }

    /// Stages the instance records in the frame's ring slot (copied at the frame's start, before
    /// `record_tlas` reads them).
    pub fn write_instances(&self, up: &mut Uploads, scene: &Scene) -> Result<()> {
        let dynamic = self.dynamic.as_ref();
        let records: Vec<vk::AccelerationStructureInstanceKHR> = scene
            .instances
            .iter()
            .enumerate()
            .map(|(i, inst)| {
                let blas = match inst.skinned {
                    Some(slot) => dynamic.map(|d| &d.blases[slot].accel),
                    None => self.blases[inst.mesh][inst.primitive].as_ref(),
                };
                let mut flags = vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE;
                flags |= if instance_opaque(scene, inst) {
                    vk::GeometryInstanceFlagsKHR::FORCE_OPAQUE
                } else {
                    vk::GeometryInstanceFlagsKHR::FORCE_NO_OPAQUE
                };
                let mask = if blas.is_some() { instance_mask(scene, inst) } else { 0 };
                let t = self.origin.matrix(&inst.world).transpose().to_cols_array();
                vk::AccelerationStructureInstanceKHR {
                    transform: vk::TransformMatrixKHR { matrix: t[..12].try_into().unwrap() },
                    instance_custom_index_and_mask: vk::Packed24_8::new(i as u32, mask),
                    instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                        0,
                        flags.as_raw() as u8,
                    ),
                    acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                        device_handle: blas.map(|b| b.address).unwrap_or(0),
                    },
                }
            })
            .collect();
        // SAFETY: AccelerationStructureInstanceKHR is plain old data (repr(C), 64 bytes).
        let bytes = unsafe {
            std::slice::from_raw_parts(
                records.as_ptr() as *const u8,
                std::mem::size_of_val(records.as_slice()),
            )
        };
        up.write(&self.instances, 0, bytes)
    }

    /// Records the TLAS build over the instance records `write_instances` staged, growing the TLAS first if
    /// it must.
    pub fn record_tlas(&mut self, ctx: &Context, cmd: vk::CommandBuffer, scene: &Scene) -> Result<()> {
        let loader = ctx.accel.as_ref().context("acceleration structures are not enabled")?;
        let count = scene.instances.len() as u32;

        let geoms = [vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR {
                instances: vk::AccelerationStructureGeometryInstancesDataKHR::default()
                    .data(vk::DeviceOrHostAddressConstKHR { device_address: self.instances.address }),
            })];
        let mut info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geoms);
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        unsafe {
            loader.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                &[count],
                &mut sizes,
            )
        };
        if self.tlas.buffer.size < sizes.acceleration_structure_size {
            // A frame in flight may still trace the old TLAS (the instance count is fixed, so this is the
            // load-time build).
            unsafe { ctx.device.device_wait_idle() }.context("vkDeviceWaitIdle before growing the TLAS")?;
            self.tlas.destroy(ctx);
            self.tlas = AccelStruct::new(
                ctx,
                "TLAS",
                vk::AccelerationStructureTypeKHR::TOP_LEVEL,
                sizes.acceleration_structure_size,
            )?;
        }
        let scratch = self.scratch.address(ctx, sizes.build_scratch_size)?;
        info = info
            .dst_acceleration_structure(self.tlas.raw)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch });
        let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count)];
        let build = vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR;
        // (The ring's upload barrier made the instance records visible.)
        unsafe { loader.cmd_build_acceleration_structures(cmd, &[info], &[&range]) };
        // The tracing passes (this frame's or later submissions') read it.
        let mut tracers = vk::PipelineStageFlags2::COMPUTE_SHADER;
        if ctx.rt.ray_tracing_pipeline {
            tracers |= vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR;
        }
        memory_barrier(
            ctx,
            cmd,
            (build, vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR),
            (tracers, vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR),
        );
        Ok(())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for row in &mut self.blases {
            for b in row.iter_mut().flatten() {
                b.destroy(ctx);
            }
        }
        self.tlas.destroy(ctx);
        if let Some(d) = &mut self.dynamic {
            d.destroy(ctx);
        }
        self.instances.destroy(ctx);
        self.scratch.destroy(ctx);
    }
}

crate::destroy_by_method!(SceneAccel);
