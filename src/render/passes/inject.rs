//! Pass `inject` (tests only): overwrites a few HDR pixels after `composite` with NaN, Inf, 1e30..., so
//! later passes are tested on radiance no sanitized scene produces (glsl/inject.comp). Runs only while
//! `Renderer::inject_radiance` has armed it.

use anyhow::Result;
use ash::vk;

use super::composite::HDR;
use super::{Creation, Pass, PassDesc, Recording};
use crate::gpu::shared::{INJECT_HDR, INJECT_MAX};
use crate::render::frame::{Access, Use};
use crate::render::targets::Targets;
use crate::vk::pipeline::{
    bind_compute, compute_pipeline, pipeline_layout, Binding, DescriptorSet, Specialization,
};
use crate::vk::{built, Context};

/// One overwritten pixel: (x, y) and its RGB radiance.
pub type Injected = ([u32; 2], [f32; 3]);

/// Checks a set of pixels before it is armed.
pub fn check(pixels: &[Injected]) -> Result<()> {
    anyhow::ensure!(
        pixels.len() <= INJECT_MAX as usize,
        "at most {INJECT_MAX} injected pixels, not {}",
        pixels.len()
    );
    Ok(())
}

pub const PASS: PassDesc = PassDesc {
    name: "inject",
    this_frame: super::every_frame,
    skip: |c| (!c.inject).then_some("no fault injection armed (tests only)"),
    uses: |_, _| vec![Use::image(&HDR, Access::StorageWrite)],
    create: |i: &Creation| Ok(Box::new(Inject::create(i.ctx, i.targets)?)),
};

struct Inject {
    set: DescriptorSet,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

impl Inject {
    fn create(ctx: &Context, targets: &Targets) -> Result<Inject> {
        let set = DescriptorSet::numbered(
            ctx,
            "inject set",
            &[(INJECT_HDR, Binding::one(vk::DescriptorType::STORAGE_IMAGE))],
        )?;
        let pass = Inject { set, layout: vk::PipelineLayout::null(), pipeline: vk::Pipeline::null() };
        let pass = built(ctx, pass, |p| {
            p.layout = pipeline_layout(ctx, "inject layout", &[p.set.layout], 128)?;
            p.pipeline = compute_pipeline(ctx, "inject.comp", p.layout, &Specialization::new(&[]))?;
            Ok(())
        })?;
        pass.bind(ctx, targets);
        Ok(pass)
    }
}

impl Pass for Inject {
    fn stage(&self) -> vk::PipelineStageFlags2 {
        vk::PipelineStageFlags2::COMPUTE_SHADER
    }

    fn record(&self, cx: &Recording, cmd: vk::CommandBuffer) {
        let ctx = cx.ctx;
        // Pixel i: its coordinates in words 4i, 4i + 1 (word 2 holds the
        // count), its radiance in words 16 + 4i ...
        let mut push = [0u32; 32];
        for (i, (xy, v)) in cx.injected.iter().enumerate() {
            push[i * 4] = xy[0];
            push[i * 4 + 1] = xy[1];
            for c in 0..3 {
                push[16 + i * 4 + c] = v[c].to_bits();
            }
        }
        push[2] = cx.injected.len() as u32;
        bind_compute(ctx, cmd, self.pipeline, self.layout, &[self.set.set]);
        unsafe {
            ctx.device.cmd_push_constants(
                cmd,
                self.layout,
                vk::ShaderStageFlags::ALL,
                0,
                bytemuck::cast_slice(&push),
            );
            ctx.device.cmd_dispatch(cmd, 1, 1, 1);
        }
    }

    fn bind(&self, ctx: &Context, targets: &Targets) {
        if let Some(hdr) = targets.get(&HDR) {
            self.set.write_image(ctx, INJECT_HDR, 0, hdr.view, vk::Sampler::null(), vk::ImageLayout::GENERAL);
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_pipeline(self.pipeline, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        self.set.destroy(ctx);
    }
}
