//! Fault injection for tests: overwrites a few pixels of the HDR frame
//! after `composite` with chosen values (NaN, Inf, 1e30), so the passes
//! after it are tested on radiance that no sanitized scene input produces
//! (glsl/inject.comp). Recorded only while armed; never in a normal frame.

use anyhow::Result;
use ash::vk;

use super::frame::{Access, Recorder, Use};
use super::passes::composite::HDR;
use super::targets::Targets;
use crate::gpu::shared::{INJECT_HDR, INJECT_MAX};
use crate::vk::pipeline::{
    bind_compute, compute_pipeline, pipeline_layout, Binding, DescriptorSet, Specialization,
};
use crate::vk::Context;

/// One overwritten pixel: (x, y) and its RGB radiance.
pub type Injected = ([u32; 2], [f32; 3]);

pub struct Injection {
    pixels: Vec<Injected>,
    set: DescriptorSet,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

impl Injection {
    pub fn new(ctx: &Context, pixels: &[Injected]) -> Result<Injection> {
        anyhow::ensure!(
            !pixels.is_empty() && pixels.len() <= INJECT_MAX as usize,
            "1 to {INJECT_MAX} injected pixels, not {}",
            pixels.len()
        );
        let set = DescriptorSet::numbered(
            ctx,
            "inject set",
            &[(INJECT_HDR, Binding::one(vk::DescriptorType::STORAGE_IMAGE))],
        )?;
        let mut inj = Injection {
            pixels: pixels.to_vec(),
            set,
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        };
        let made = pipeline_layout(ctx, "inject layout", &[inj.set.layout], 128).and_then(|l| {
            inj.layout = l;
            compute_pipeline(ctx, "inject.comp", l, &Specialization::new(&[]))
        });
        match made {
            Ok(p) => inj.pipeline = p,
            Err(e) => {
                inj.destroy(ctx);
                return Err(e);
            }
        }
        Ok(inj)
    }

    /// Records the overwrite of the HDR target as pass "inject".
    pub fn record(&self, rec: &mut Recorder, targets: &Targets) -> Result<()> {
        let ctx = rec.ctx;
        let hdr = targets.get(&HDR).ok_or_else(|| anyhow::anyhow!("no HDR target to inject into"))?;
        self.set.write_image(ctx, INJECT_HDR, 0, hdr.view, vk::Sampler::null(), vk::ImageLayout::GENERAL);
        let mut push = [0u32; 32];
        for (i, (xy, v)) in self.pixels.iter().enumerate() {
            push[i * 4] = xy[0];
            push[i * 4 + 1] = xy[1];
            for c in 0..3 {
                push[16 + i * 4 + c] = v[c].to_bits();
            }
        }
        push[2] = self.pixels.len() as u32;
        let uses = [Use::image(&HDR, Access::StorageWrite)];
        let (pipeline, layout, set) = (self.pipeline, self.layout, self.set.set);
        rec.pass("inject", vk::PipelineStageFlags2::COMPUTE_SHADER, &uses, |cmd| {
            bind_compute(ctx, cmd, pipeline, layout, &[set]);
            unsafe {
                ctx.device.cmd_push_constants(
                    cmd,
                    layout,
                    vk::ShaderStageFlags::ALL,
                    0,
                    bytemuck::cast_slice(&push),
                );
                ctx.device.cmd_dispatch(cmd, 1, 1, 1);
            }
            Ok(())
        })
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_pipeline(self.pipeline, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        self.set.destroy(ctx);
    }
}
