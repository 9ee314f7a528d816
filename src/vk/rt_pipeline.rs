//! Ray-tracing pipeline (VK_KHR_ray_tracing_pipeline): one ray-generation shader, the miss shaders and
//! triangle hit groups its caller names, and a shader binding table laid out from the driver's handle
//! size and alignments (regions raygen, miss, hit).

use anyhow::{Context as _, Result};
use ash::{khr, vk};
use gpu_allocator::MemoryLocation;

use super::pipeline::{shader_module, Specialization};
use super::{Buffer, Context};

/// The shaders of a pipeline, by name in the build's shader table.
pub struct RtShaders<'a> {
    pub raygen: &'a str,
    pub miss: &'a [&'a str],
    /// Triangle hit groups in SBT order: (closest hit, any hit).
    pub hit_groups: &'a [(Option<&'a str>, Option<&'a str>)],
}

pub struct RtPipeline {
    pub pipeline: vk::Pipeline,
    sbt: Buffer,
    /// raygen, miss, hit, callable.
    regions: [vk::StridedDeviceAddressRegionKHR; 4],
}

fn align_up(x: u64, a: u64) -> u64 {
    x.div_ceil(a.max(1)) * a.max(1)
}

impl RtPipeline {
    pub fn new<'a>(
        ctx: &Context,
        shaders: &RtShaders<'a>,
        layout: vk::PipelineLayout,
        spec: &Specialization,
    ) -> Result<RtPipeline> {
        let loader = ctx.rt_pipeline.as_ref().context("ray-tracing pipelines are not enabled")?;
        let mut props = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
        let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut props);
        unsafe { ctx.instance.raw.get_physical_device_properties2(ctx.physical_device, &mut p2) };

        // Stage list: raygen, misses, then each hit group's shaders.
        let mut names = vec![(shaders.raygen, vk::ShaderStageFlags::RAYGEN_KHR)];
        names.extend(shaders.miss.iter().map(|m| (*m, vk::ShaderStageFlags::MISS_KHR)));
        let unused = vk::SHADER_UNUSED_KHR;
        let general = |i: u32| {
            vk::RayTracingShaderGroupCreateInfoKHR::default()
                .ty(vk::RayTracingShaderGroupTypeKHR::GENERAL)
                .general_shader(i)
                .closest_hit_shader(unused)
                .any_hit_shader(unused)
                .intersection_shader(unused)
        };
        let mut groups = vec![general(0)];
        groups.extend((0..shaders.miss.len() as u32).map(|i| general(1 + i)));
        for (closest, any) in shaders.hit_groups {
            let mut index = |name: &Option<&'a str>, stage| match name {
                Some(n) => {
                    names.push((*n, stage));
                    names.len() as u32 - 1
                }
                None => unused,
            };
            let c = index(closest, vk::ShaderStageFlags::CLOSEST_HIT_KHR);
            let a = index(any, vk::ShaderStageFlags::ANY_HIT_KHR);
            groups.push(
                vk::RayTracingShaderGroupCreateInfoKHR::default()
                    .ty(vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP)
                    .general_shader(unused)
                    .closest_hit_shader(c)
                    .any_hit_shader(a)
                    .intersection_shader(unused),
            );
        }
        let modules = names.iter().map(|(n, _)| shader_module(ctx, n)).collect::<Result<Vec<_>>>()?;
        let spec_info = spec.info();
        let stages: Vec<_> = modules
            .iter()
            .zip(&names)
            .enumerate()
            .map(|(i, (m, (_, f)))| {
                let s = vk::PipelineShaderStageCreateInfo::default().stage(*f).module(*m).name(c"main");
                if i == 0 {
                    s.specialization_info(&spec_info)
                } else {
                    s
                }
            })
            .collect();
        let info = [vk::RayTracingPipelineCreateInfoKHR::default()
            .stages(&stages)
            .groups(&groups)
            .max_pipeline_ray_recursion_depth(1)
            .layout(layout)];
        let r = unsafe {
            loader.create_ray_tracing_pipelines(
                vk::DeferredOperationKHR::null(),
                vk::PipelineCache::null(),
                &info,
                None,
            )
        };
        for m in modules {
            unsafe { ctx.device.destroy_shader_module(m, None) };
        }
        let pipeline = r.map_err(|(_, e)| e).context("create ray-tracing pipeline")?[0];
        ctx.name(pipeline, shaders.raygen);
        Self::with_sbt(ctx, loader, shaders, pipeline, groups.len(), &props)
            .inspect_err(|_| unsafe { ctx.device.destroy_pipeline(pipeline, None) })
    }

    /// Builds the shader binding table of `pipeline`.
    fn with_sbt(
        ctx: &Context,
        loader: &khr::ray_tracing_pipeline::Device,
        shaders: &RtShaders,
        pipeline: vk::Pipeline,
        group_count: usize,
        props: &vk::PhysicalDeviceRayTracingPipelinePropertiesKHR,
    ) -> Result<RtPipeline> {
        // Each region starts at the base alignment; records are the handle size rounded up to the handle
        // alignment.
        let handle = props.shader_group_handle_size as u64;
        let stride = align_up(handle, props.shader_group_handle_alignment as u64);
        let base = props.shader_group_base_alignment as u64;
        let handles = unsafe {
            loader.get_ray_tracing_shader_group_handles(
                pipeline,
                0,
                group_count as u32,
                group_count * handle as usize,
            )?
        };
        let (n_miss, n_hit) = (shaders.miss.len() as u64, shaders.hit_groups.len() as u64);
        let raygen_size = align_up(stride, base);
        let miss_off = raygen_size;
        let miss_size = align_up(n_miss * stride, base);
        let hit_off = miss_off + miss_size;
        let hit_size = align_up(n_hit * stride, base);
        let total = hit_off + hit_size;
        let mut data = vec![0u8; total as usize];
        let copy = |data: &mut Vec<u8>, group: usize, at: u64| {
            let h = &handles[group * handle as usize..(group + 1) * handle as usize];
            data[at as usize..(at + handle) as usize].copy_from_slice(h);
        };
        copy(&mut data, 0, 0);
        for i in 0..n_miss {
            copy(&mut data, 1 + i as usize, miss_off + i * stride);
        }
        for i in 0..n_hit {
            copy(&mut data, (1 + n_miss + i) as usize, hit_off + i * stride);
        }
        // Extra room so the table's start can be moved to the base alignment.
        let mut sbt = Buffer::new(
            ctx,
            "shader binding table",
            total + base,
            vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            MemoryLocation::CpuToGpu,
        )?;
        let start = align_up(sbt.address, base);
        sbt.write((start - sbt.address) as usize, &data).inspect_err(|_| sbt.destroy(ctx))?;
        let region = |off: u64, stride: u64, size: u64| vk::StridedDeviceAddressRegionKHR {
            device_address: start + off,
            stride,
            size,
        };
        let regions = [
            region(0, raygen_size, raygen_size), // raygen: stride must equal size
            region(miss_off, stride, n_miss * stride),
            region(hit_off, stride, n_hit * stride),
            vk::StridedDeviceAddressRegionKHR::default(),
        ];
        Ok(RtPipeline { pipeline, sbt, regions })
    }

    pub fn trace(&self, ctx: &Context, cmd: vk::CommandBuffer, width: u32, height: u32) {
        if let Some(loader) = ctx.rt_pipeline.as_ref() {
            let [rg, miss, hit, call] = &self.regions;
            unsafe { loader.cmd_trace_rays(cmd, rg, miss, hit, call, width, height, 1) };
        }
    }

    /// Launches with the VkTraceRaysIndirectCommandKHR at device address
    /// `command` (needs rayTracingPipelineTraceRaysIndirect).
    pub fn trace_indirect(&self, ctx: &Context, cmd: vk::CommandBuffer, command: vk::DeviceAddress) {
        if let Some(loader) = ctx.rt_pipeline.as_ref() {
            let [rg, miss, hit, call] = &self.regions;
            unsafe { loader.cmd_trace_rays_indirect(cmd, rg, miss, hit, call, command) };
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe { ctx.device.destroy_pipeline(self.pipeline, None) };
        self.sbt.destroy(ctx);
    }
}

/// Loader for the extension's device functions.
pub fn loader(ctx_instance: &ash::Instance, device: &ash::Device) -> khr::ray_tracing_pipeline::Device {
    khr::ray_tracing_pipeline::Device::new(ctx_instance, device)
}
