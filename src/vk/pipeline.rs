//! Shader modules from the build-time SPIR-V table, pipeline layouts,
//! compute pipelines and descriptor-set plumbing.

use anyhow::{Context as _, Result};
use ash::vk;

use super::Context;

mod table {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

/// SPIR-V words of a shader compiled by build.rs (name = path under glsl/,
/// or a variant name from glsl/variants.txt).
pub fn spirv(name: &str) -> Result<Vec<u32>> {
    let bytes = table::SHADERS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, b)| *b)
        .with_context(|| format!("shader '{name}' was not compiled into the binary"))?;
    Ok(ash::util::read_spv(&mut std::io::Cursor::new(bytes))?)
}

pub fn shader_module(ctx: &Context, name: &str) -> Result<vk::ShaderModule> {
    let code = spirv(name)?;
    let m =
        unsafe { ctx.device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)? };
    ctx.name(m, name);
    Ok(m)
}

/// Specialization constants: (constant id, u32 value).
pub struct Specialization {
    entries: Vec<vk::SpecializationMapEntry>,
    data: Vec<u8>,
}

impl Specialization {
    /// `values`: (constant id, 32-bit value; use `f32::to_bits` for floats).
    pub fn new(values: &[(u32, u32)]) -> Specialization {
        let entries = values
            .iter()
            .enumerate()
            .map(|(i, (id, _))| vk::SpecializationMapEntry {
                constant_id: *id,
                offset: 4 * i as u32,
                size: 4,
            })
            .collect();
        let data = values.iter().flat_map(|(_, v)| v.to_ne_bytes()).collect();
        Specialization { entries, data }
    }
    pub fn info(&self) -> vk::SpecializationInfo<'_> {
        vk::SpecializationInfo::default().map_entries(&self.entries).data(&self.data)
    }
}

pub fn pipeline_layout(
    ctx: &Context,
    name: &str,
    sets: &[vk::DescriptorSetLayout],
    push_bytes: u32,
) -> Result<vk::PipelineLayout> {
    let ranges = [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::ALL).size(push_bytes)];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(sets);
    if push_bytes > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    let l = unsafe { ctx.device.create_pipeline_layout(&info, None)? };
    ctx.name(l, name);
    Ok(l)
}

pub fn compute_pipeline(
    ctx: &Context,
    shader: &str,
    layout: vk::PipelineLayout,
    spec: &Specialization,
) -> Result<vk::Pipeline> {
    let module = shader_module(ctx, shader)?;
    let spec_info = spec.info();
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module)
        .name(c"main")
        .specialization_info(&spec_info);
    let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
    let r = unsafe { ctx.device.create_compute_pipelines(vk::PipelineCache::null(), &info, None) };
    unsafe { ctx.device.destroy_shader_module(module, None) };
    let p = r.map_err(|(_, e)| e).with_context(|| format!("create compute pipeline '{shader}'"))?[0];
    ctx.name(p, shader);
    Ok(p)
}

/// Binds a compute pipeline and its descriptor sets (from set 0).
pub fn bind_compute(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    pipeline: vk::Pipeline,
    layout: vk::PipelineLayout,
    sets: &[vk::DescriptorSet],
) {
    unsafe {
        ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
        ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, layout, 0, sets, &[]);
    }
}

/// One binding of a descriptor-set layout.
#[derive(Clone, Copy)]
pub struct Binding {
    pub ty: vk::DescriptorType,
    pub count: u32,
    /// A runtime-sized, partially bound array (bindless textures). Last binding only.
    pub bindless: bool,
}

impl Binding {
    pub const fn one(ty: vk::DescriptorType) -> Binding {
        Binding { ty, count: 1, bindless: false }
    }
}

/// A descriptor-set layout plus a pool holding exactly one set of it.
pub struct DescriptorSet {
    pub layout: vk::DescriptorSetLayout,
    pub pool: vk::DescriptorPool,
    pub set: vk::DescriptorSet,
    bindings: Vec<(u32, Binding)>,
}

impl DescriptorSet {
    /// A set that owns nothing (a placeholder; `destroy` is a no-op).
    pub fn null() -> DescriptorSet {
        DescriptorSet {
            layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            bindings: Vec::new(),
        }
    }

    /// Bindings numbered 0, 1, 2, ... in order.
    pub fn new(ctx: &Context, name: &str, bindings: &[Binding]) -> Result<DescriptorSet> {
        let numbered: Vec<(u32, Binding)> =
            bindings.iter().enumerate().map(|(i, b)| (i as u32, *b)).collect();
        Self::numbered(ctx, name, &numbered)
    }

    /// Bindings with explicit numbers (gaps allowed; a bindless one last).
    pub fn numbered(ctx: &Context, name: &str, numbered: &[(u32, Binding)]) -> Result<DescriptorSet> {
        let stages = vk::ShaderStageFlags::ALL;
        let raw: Vec<_> = numbered
            .iter()
            .map(|(i, b)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(*i)
                    .descriptor_type(b.ty)
                    .descriptor_count(b.count.max(1))
                    .stage_flags(stages)
            })
            .collect();
        let bindings: Vec<Binding> = numbered.iter().map(|(_, b)| *b).collect();
        let flags: Vec<_> = bindings
            .iter()
            .map(|b| {
                if b.bindless {
                    vk::DescriptorBindingFlags::PARTIALLY_BOUND
                        | vk::DescriptorBindingFlags::VARIABLE_DESCRIPTOR_COUNT
                } else {
                    vk::DescriptorBindingFlags::empty()
                }
            })
            .collect();
        let mut flag_info = vk::DescriptorSetLayoutBindingFlagsCreateInfo::default().binding_flags(&flags);
        let layout = unsafe {
            ctx.device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&raw).push_next(&mut flag_info),
                None,
            )?
        };
        ctx.name(layout, &format!("{name} layout"));
        let sizes: Vec<_> = bindings
            .iter()
            .map(|b| vk::DescriptorPoolSize { ty: b.ty, descriptor_count: b.count.max(1) })
            .collect();
        let pool = unsafe {
            ctx.device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                None,
            )?
        };
        ctx.name(pool, &format!("{name} pool"));
        let layouts = [layout];
        let variable = [bindings.last().filter(|b| b.bindless).map(|b| b.count.max(1)).unwrap_or(0)];
        let mut var_info =
            vk::DescriptorSetVariableDescriptorCountAllocateInfo::default().descriptor_counts(&variable);
        let mut alloc = vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts);
        if bindings.last().is_some_and(|b| b.bindless) {
            alloc = alloc.push_next(&mut var_info);
        }
        let set = unsafe { ctx.device.allocate_descriptor_sets(&alloc)? }[0];
        ctx.name(set, name);
        Ok(DescriptorSet { layout, pool, set, bindings: numbered.to_vec() })
    }

    /// A set of storage buffers at the given binding numbers, written.
    pub fn storage_buffers(
        ctx: &Context,
        name: &str,
        buffers: &[(u32, vk::Buffer)],
    ) -> Result<DescriptorSet> {
        let sb = Binding::one(vk::DescriptorType::STORAGE_BUFFER);
        let numbered: Vec<(u32, Binding)> = buffers.iter().map(|(b, _)| (*b, sb)).collect();
        let set = Self::numbered(ctx, name, &numbered)?;
        for (b, buffer) in buffers {
            set.write_buffer(ctx, *b, *buffer);
        }
        Ok(set)
    }

    fn binding_type(&self, binding: u32) -> vk::DescriptorType {
        self.bindings.iter().find(|(i, _)| *i == binding).map(|(_, b)| b.ty).unwrap_or_else(|| {
            panic!("descriptor set has no binding {binding}") // a programming error, not input
        })
    }

    pub fn write_buffer(&self, ctx: &Context, binding: u32, buffer: vk::Buffer) {
        let info = [vk::DescriptorBufferInfo::default().buffer(buffer).range(vk::WHOLE_SIZE)];
        let w = vk::WriteDescriptorSet::default()
            .dst_set(self.set)
            .dst_binding(binding)
            .descriptor_type(self.binding_type(binding))
            .buffer_info(&info);
        unsafe { ctx.device.update_descriptor_sets(&[w], &[]) };
    }

    pub fn write_image(
        &self,
        ctx: &Context,
        binding: u32,
        element: u32,
        view: vk::ImageView,
        sampler: vk::Sampler,
        layout: vk::ImageLayout,
    ) {
        let info =
            [vk::DescriptorImageInfo::default().image_view(view).sampler(sampler).image_layout(layout)];
        let w = vk::WriteDescriptorSet::default()
            .dst_set(self.set)
            .dst_binding(binding)
            .dst_array_element(element)
            .descriptor_type(self.binding_type(binding))
            .image_info(&info);
        unsafe { ctx.device.update_descriptor_sets(&[w], &[]) };
    }

    pub fn write_acceleration_structure(
        &self,
        ctx: &Context,
        binding: u32,
        accel: vk::AccelerationStructureKHR,
    ) {
        let structures = [accel];
        let mut info =
            vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(&structures);
        let mut w = vk::WriteDescriptorSet::default()
            .dst_set(self.set)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
            .push_next(&mut info);
        w.descriptor_count = 1;
        unsafe { ctx.device.update_descriptor_sets(&[w], &[]) };
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_descriptor_pool(self.pool, None);
            ctx.device.destroy_descriptor_set_layout(self.layout, None);
        }
        self.pool = vk::DescriptorPool::null();
        self.layout = vk::DescriptorSetLayout::null();
    }
}
