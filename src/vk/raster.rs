//! Graphics pipelines for the raster passes, which share their shape: vertex pulling (no vertex input),
//! triangle lists, one dynamic viewport and scissor, one sample, depth test and write, dynamic
//! rendering. What differs between passes is in [`RasterPipeline`].

use anyhow::{Context as _, Result};
use ash::vk;

use super::pipeline::{shader_module, Specialization};
use super::Context;

/// What a raster pass chooses.
pub struct RasterPipeline<'a> {
    /// Debug name (also in the error context).
    pub name: &'a str,
    pub vertex: &'a str,
    /// The fragment shader and its specialization; None: depth only.
    pub fragment: Option<(&'a str, &'a Specialization)>,
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
    pub depth_compare: vk::CompareOp,
    /// Cull mode (counter-clockwise front faces), or `None` for cull mode and front face set per draw.
    pub cull: Option<vk::CullModeFlags>,
    /// Slope-scaled depth bias (shadow maps).
    pub slope_bias: Option<f32>,
}

impl RasterPipeline<'_> {
    pub fn create(&self, ctx: &Context, layout: vk::PipelineLayout) -> Result<vk::Pipeline> {
        let mut modules = Modules { ctx, list: Vec::new() };
        let vs = modules.load(self.vertex)?;
        let fs = self.fragment.map(|(name, _)| modules.load(name)).transpose()?;
        let spec_info = self.fragment.map(|(_, spec)| spec.info());
        let mut stages = vec![vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vs)
            .name(c"main")];
        if let (Some(fs), Some(spec_info)) = (fs, spec_info.as_ref()) {
            stages.push(
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::FRAGMENT)
                    .module(fs)
                    .name(c"main")
                    .specialization_info(spec_info),
            );
        }
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default(); // vertex pulling
        let ia = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let vp = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let mut rs = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(self.cull.unwrap_or(vk::CullModeFlags::BACK))
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        if let Some(slope) = self.slope_bias {
            rs = rs.depth_bias_enable(true).depth_bias_constant_factor(0.0).depth_bias_slope_factor(slope);
        }
        let ms = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let ds = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(self.depth_compare);
        let blend: Vec<_> = self
            .color_formats
            .iter()
            .map(|_| {
                vk::PipelineColorBlendAttachmentState::default()
                    .color_write_mask(vk::ColorComponentFlags::RGBA)
            })
            .collect();
        let cb = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let mut dynamic = vec![vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        if self.cull.is_none() {
            dynamic.extend([vk::DynamicState::CULL_MODE, vk::DynamicState::FRONT_FACE]);
        }
        let dyn_state = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(self.color_formats)
            .depth_attachment_format(self.depth_format);
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&ia)
            .viewport_state(&vp)
            .rasterization_state(&rs)
            .multisample_state(&ms)
            .depth_stencil_state(&ds)
            .color_blend_state(&cb)
            .dynamic_state(&dyn_state)
            .layout(layout)
            .push_next(&mut rendering)];
        let r = unsafe { ctx.device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
        let p = r.map_err(|(_, e)| e).with_context(|| format!("create {} pipeline", self.name))?[0];
        ctx.name(p, self.name);
        Ok(p)
    }
}

/// The shader modules of one pipeline: needed only until it is created, and destroyed on every path out
/// of `create`.
struct Modules<'a> {
    ctx: &'a Context,
    list: Vec<vk::ShaderModule>,
}

impl Modules<'_> {
    fn load(&mut self, name: &str) -> Result<vk::ShaderModule> {
        let m = shader_module(self.ctx, name)?;
        self.list.push(m);
        Ok(m)
    }
}

impl Drop for Modules<'_> {
    fn drop(&mut self) {
        for m in self.list.drain(..) {
            unsafe { self.ctx.device.destroy_shader_module(m, None) };
        }
    }
}
