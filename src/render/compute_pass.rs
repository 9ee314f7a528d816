//! A full-screen pass: scene set 0, its own set 1 of images, optional extra
//! sets, and either a compute pipeline (8x8 workgroups) or a ray-tracing
//! pipeline launched one ray-generation invocation per pixel. Lighting (in
//! every backend) and tone mapping are these.

use anyhow::Result;
use ash::vk;

use crate::vk::pipeline::{compute_pipeline, pipeline_layout, Binding, DescriptorSet, Specialization};
use crate::vk::rt_pipeline::RtPipeline;
use crate::vk::Context;

/// How one set-1 binding is fed.
#[derive(Clone, Copy)]
pub enum Input {
    /// texelFetch from a sampled image in SHADER_READ_ONLY_OPTIMAL.
    Sampled(vk::ImageView),
    /// imageLoad / imageStore on an image in GENERAL.
    Storage(vk::ImageView),
}

enum Kernel {
    Compute(vk::Pipeline),
    RayTracing(RtPipeline),
}

pub struct ComputePass {
    pub name: &'static str,
    layout: vk::PipelineLayout,
    kernel: Kernel,
    set: DescriptorSet,
    sampler: vk::Sampler,
}

impl ComputePass {
    pub fn new(
        ctx: &Context,
        name: &'static str,
        shader: &str,
        scene_layout: vk::DescriptorSetLayout,
        inputs: &[Input],
        extra_sets: &[vk::DescriptorSetLayout],
        spec: &Specialization,
    ) -> Result<ComputePass> {
        let bindings: Vec<_> = inputs
            .iter()
            .map(|i| match i {
                Input::Sampled(_) => Binding::one(vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
                Input::Storage(_) => Binding::one(vk::DescriptorType::STORAGE_IMAGE),
            })
            .collect();
        let set = DescriptorSet::new(ctx, &format!("{name} set"), &bindings)?;
        let mut sets = vec![scene_layout, set.layout];
        sets.extend_from_slice(extra_sets);
        let layout = pipeline_layout(ctx, &format!("{name} layout"), &sets, 0)?;
        // A ray-generation shader makes this a ray-tracing pass.
        let kernel = if shader.ends_with(".rgen") || shader.starts_with("rt_pipeline") {
            Kernel::RayTracing(RtPipeline::new(ctx, shader, layout, spec)?)
        } else {
            Kernel::Compute(compute_pipeline(ctx, shader, layout, spec)?)
        };
        let sampler = unsafe {
            ctx.device.create_sampler(
                &vk::SamplerCreateInfo::default()
                    .mag_filter(vk::Filter::NEAREST)
                    .min_filter(vk::Filter::NEAREST)
                    .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                    .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE),
                None,
            )?
        };
        ctx.name(sampler, &format!("{name} point sampler"));
        let pass = ComputePass { name, layout, kernel, set, sampler };
        pass.bind(ctx, inputs);
        Ok(pass)
    }

    /// Points set 1 at (new) images, e.g. after a resize.
    pub fn bind(&self, ctx: &Context, inputs: &[Input]) {
        for (i, input) in inputs.iter().enumerate() {
            match input {
                Input::Sampled(v) => self.set.write_image(
                    ctx,
                    i as u32,
                    0,
                    *v,
                    self.sampler,
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                ),
                Input::Storage(v) => {
                    self.set.write_image(ctx, i as u32, 0, *v, vk::Sampler::null(), vk::ImageLayout::GENERAL)
                }
            }
        }
    }

    /// Binds set 0 (scene), set 1 (this pass's images), then `extra` sets
    /// from set 2 on, and dispatches one thread per pixel.
    pub fn dispatch(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        scene_set: vk::DescriptorSet,
        extra: &[vk::DescriptorSet],
        extent: vk::Extent2D,
    ) {
        let d = &ctx.device;
        let mut sets = vec![scene_set, self.set.set];
        sets.extend_from_slice(extra);
        let (bind_point, pipeline) = match &self.kernel {
            Kernel::Compute(p) => (vk::PipelineBindPoint::COMPUTE, *p),
            Kernel::RayTracing(rt) => (vk::PipelineBindPoint::RAY_TRACING_KHR, rt.pipeline),
        };
        unsafe {
            d.cmd_bind_pipeline(cmd, bind_point, pipeline);
            d.cmd_bind_descriptor_sets(cmd, bind_point, self.layout, 0, &sets, &[]);
            match &self.kernel {
                Kernel::Compute(_) => {
                    d.cmd_dispatch(cmd, extent.width.div_ceil(8), extent.height.div_ceil(8), 1)
                }
                Kernel::RayTracing(rt) => rt.trace(ctx, cmd, extent.width, extent.height),
            }
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        match &mut self.kernel {
            Kernel::Compute(p) => unsafe { ctx.device.destroy_pipeline(*p, None) },
            Kernel::RayTracing(rt) => rt.destroy(ctx),
        }
        unsafe {
            ctx.device.destroy_pipeline_layout(self.layout, None);
            ctx.device.destroy_sampler(self.sampler, None);
        }
        self.set.destroy(ctx);
    }
}
