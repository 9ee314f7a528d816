//! Pass `luminance`: log-average and histogram of the frame's luminance by GPU reduction, adapting the
//! exposure `tonemap` applies (glsl/luminance.comp): LUMINANCE_GROUPS groups write partial sums, then
//! one group updates the state in set 0's exposure buffer. Left out when the exposure is fixed and no
//! operator needs the frame's maximum.

use anyhow::Result;
use ash::vk;

use super::composite::HDR;
use super::{Creation, Pass, PassDesc, Recording};
use crate::gpu::shared::{LUMINANCE_GROUPS, LUMINANCE_IN, SPEC_LUMINANCE_STAGE};
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::shading::ShadingConfig;
use crate::render::targets::Targets;
use crate::vk::pipeline::{
    bind_compute, compute_pipeline, pipeline_layout, Binding, DescriptorSet, Specialization,
};
use crate::vk::{built, Context};

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    (!c.luminance).then_some("fixed exposure: no luminance is measured")
}

pub const PASS: PassDesc = PassDesc {
    name: "luminance",
    this_frame: super::every_frame,
    skip,
    uses: |_, _| {
        vec![Use::image(&HDR, Access::StorageRead), Use::buffer(SharedBuffer::Exposure, Access::ShaderWrite)]
    },
    create: |i: &Creation| Ok(Box::new(Luminance::create(i.ctx, i.gpu.set.layout, i.targets)?)),
};

struct Luminance {
    set: DescriptorSet,
    layout: vk::PipelineLayout,
    /// Stage 0 (partial sums) and stage 1 (combine + adapt).
    pipelines: [vk::Pipeline; 2],
}

impl Luminance {
    fn create(ctx: &Context, scene_layout: vk::DescriptorSetLayout, targets: &Targets) -> Result<Luminance> {
        let set = DescriptorSet::numbered(
            ctx,
            "luminance set",
            &[(LUMINANCE_IN, Binding::one(vk::DescriptorType::STORAGE_IMAGE))],
        )?;
        let pass =
            Luminance { set, layout: vk::PipelineLayout::null(), pipelines: [vk::Pipeline::null(); 2] };
        let pass = built(ctx, pass, |p| p.fill(ctx, scene_layout))?;
        pass.bind(ctx, targets);
        Ok(pass)
    }

    fn fill(&mut self, ctx: &Context, scene_layout: vk::DescriptorSetLayout) -> Result<()> {
        self.layout = pipeline_layout(ctx, "luminance layout", &[scene_layout, self.set.layout], 0)?;
        for stage in 0..2 {
            let spec = Specialization::new(&[(SPEC_LUMINANCE_STAGE, stage as u32)]);
            self.pipelines[stage] = compute_pipeline(ctx, "luminance.comp", self.layout, &spec)?;
            let what = ["partial sums", "combine + adapt"][stage];
            ctx.name(self.pipelines[stage], &format!("luminance: {what}"));
        }
        Ok(())
    }
}

impl Pass for Luminance {
    fn stage(&self) -> vk::PipelineStageFlags2 {
        vk::PipelineStageFlags2::COMPUTE_SHADER
    }

    fn record(&self, cx: &Recording, cmd: vk::CommandBuffer) {
        let ctx = cx.ctx;
        let sets = [cx.gpu.set.set, self.set.set];
        bind_compute(ctx, cmd, self.pipelines[0], self.layout, &sets);
        unsafe { ctx.device.cmd_dispatch(cmd, LUMINANCE_GROUPS, 1, 1) };
        // The partials are complete before one group combines them.
        let c = vk::PipelineStageFlags2::COMPUTE_SHADER;
        crate::vk::memory_barrier(
            ctx,
            cmd,
            (c, vk::AccessFlags2::SHADER_STORAGE_WRITE),
            (c, vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE),
        );
        bind_compute(ctx, cmd, self.pipelines[1], self.layout, &sets);
        unsafe { ctx.device.cmd_dispatch(cmd, 1, 1, 1) };
    }

    fn bind(&self, ctx: &Context, targets: &Targets) {
        if let Some(hdr) = targets.get(&HDR) {
            self.set.write_image(
                ctx,
                LUMINANCE_IN,
                0,
                hdr.view,
                vk::Sampler::null(),
                vk::ImageLayout::GENERAL,
            );
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        unsafe {
            for p in self.pipelines {
                ctx.device.destroy_pipeline(p, None);
            }
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        self.set.destroy(ctx);
    }
}
