//! Two-phase occlusion culling of the G-buffer's clusters (gpu/clusters.rs),
//! recorded inside the `gbuffer` pass (render/passes/gbuffer.rs):
//!
//! 1. `cull` phase 1 (compute): a cluster visible last frame and in the frustum gets instance count 1
//!    in phase 1's indirect draws;
//! 2. the raster draws phase 1 (depth cleared);
//! 3. `pyramid` (compute): phase 1's depth pyramid, each texel the FARTHEST (reversed-Z: minimum) depth
//!    of its pixels;
//! 4. `cull` phase 2: every cluster is tested against the pyramid (frustum, then projected box -> level
//!    -> farthest depth there); visible ones phase 1 did not draw get instance count 1 in phase 2's
//!    draws, and the visibility is kept for the next frame;
//! 5. the raster draws phase 2 (depth and hits loaded).
//!
//! Conservative: a cluster is left out only when its box lies behind everything phase 1 drew over its
//! pixels, and phase 1's depth is never nearer than the final depth, so the image is the one drawing
//! every cluster gives (up to the order of equal-depth fragments). The host still frustum-culls whole
//! draws (render/cull.rs) and sets each draw's cull mode, winding and pipeline; one multi-draw call per
//! draw and phase covers its clusters. The pyramid and the barriers between steps are private to the
//! pass; the recorder sees the `gbuffer` pass's declared uses.

use std::cell::RefCell;

use anyhow::Result;
use ash::vk;
use vk::AccessFlags2 as A;
use vk::PipelineStageFlags2 as S;

use crate::gpu::clusters::{Clusters, COMMAND_STRIDE};
use crate::gpu::shared::{HIZ_DST, HIZ_SRC, OCC_CLUSTERS, OCC_COMMANDS, OCC_COUNTERS, OCC_HIZ, OCC_VISIBLE};
use crate::gpu::GpuScene;
use crate::vk::pipeline::{
    bind_compute, compute_pipeline, pipeline_layout, Binding, DescriptorSet, Specialization,
};
use crate::vk::{built, image_barrier, memory_barrier, Context, Image};

/// The cull shader's push constants (glsl/occlusion/cull.comp).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    phase: u32,
    count: u32,
    levels: u32,
    width: u32,
    height: u32,
}

/// The depth pyramid at one target size.
struct Pyramid {
    image: Image,
    /// One view per level (the reduction writes level k, reads level k - 1).
    levels: Vec<vk::ImageView>,
    /// One set per level: its source and destination.
    sets: Vec<DescriptorSet>,
    extent: vk::Extent2D,
}

impl Pyramid {
    /// Level 0 is half the depth buffer's size (rounded up), down to 1x1.
    fn new(
        ctx: &Context,
        depth: vk::ImageView,
        sampler: vk::Sampler,
        extent: vk::Extent2D,
    ) -> Result<Pyramid> {
        let size0 =
            vk::Extent2D { width: extent.width.div_ceil(2).max(1), height: extent.height.div_ceil(2).max(1) };
        let count = 32 - size0.width.max(size0.height).leading_zeros();
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
        let image = Image::new_2d(
            ctx,
            "depth pyramid (farthest depth)",
            vk::Format::R32_SFLOAT,
            size0,
            count,
            usage,
        )?;
        let p = Pyramid { image, levels: Vec::new(), sets: Vec::new(), extent };
        built(ctx, p, |p| p.fill(ctx, depth, sampler, count))
    }

    fn fill(&mut self, ctx: &Context, depth: vk::ImageView, sampler: vk::Sampler, count: u32) -> Result<()> {
        for k in 0..count {
            let info = vk::ImageViewCreateInfo::default()
                .image(self.image.raw)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(vk::Format::R32_SFLOAT)
                .subresource_range(
                    vk::ImageSubresourceRange::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .base_mip_level(k)
                        .level_count(1)
                        .layer_count(1),
                );
            let view = unsafe { ctx.device.create_image_view(&info, None)? };
            ctx.name(view, &format!("depth pyramid level {k}"));
            self.levels.push(view);
        }
        let sampled = Binding::one(vk::DescriptorType::COMBINED_IMAGE_SAMPLER);
        let storage = Binding::one(vk::DescriptorType::STORAGE_IMAGE);
        let general = vk::ImageLayout::GENERAL;
        for k in 0..count as usize {
            let set = DescriptorSet::numbered(
                ctx,
                &format!("depth pyramid level {k}"),
                &[(HIZ_SRC, sampled), (HIZ_DST, storage)],
            )?;
            match k {
                0 => set.write_image(
                    ctx,
                    HIZ_SRC,
                    0,
                    depth,
                    sampler,
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                ),
                _ => set.write_image(ctx, HIZ_SRC, 0, self.levels[k - 1], sampler, general),
            }
            set.write_image(ctx, HIZ_DST, 0, self.levels[k], vk::Sampler::null(), general);
            self.sets.push(set);
        }
        // The pyramid stays in GENERAL: written and sampled there.
        ctx.one_shot("depth pyramid layout", |cmd| {
            let none = (S::NONE, A::NONE);
            let to = (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE | A::SHADER_SAMPLED_READ);
            let (img, aspect) = (self.image.raw, vk::ImageAspectFlags::COLOR);
            image_barrier(ctx, cmd, img, aspect, vk::ImageLayout::UNDEFINED, general, none, to);
            Ok(())
        })
    }

    fn destroy(&mut self, ctx: &Context) {
        for s in &mut self.sets {
            s.destroy(ctx);
        }
        for v in self.levels.drain(..) {
            unsafe { ctx.device.destroy_image_view(v, None) };
        }
        self.image.destroy(ctx);
    }
}

/// The culling pipelines and the depth pyramid.
pub struct Occlusion {
    /// Set 1 of the cull pass (glsl/common/cluster.glsl).
    set: DescriptorSet,
    cull_layout: vk::PipelineLayout,
    cull: vk::Pipeline,
    hiz_layout: vk::PipelineLayout,
    hiz: vk::Pipeline,
    layout_of_levels: DescriptorSet,
    sampler: vk::Sampler,
    pyramid: RefCell<Option<Pyramid>>,
}

impl Occlusion {
    pub fn new(ctx: &Context, gpu: &GpuScene, scene_layout: vk::DescriptorSetLayout) -> Result<Occlusion> {
        let c: &Clusters = &gpu.clusters;
        let sb = Binding::one(vk::DescriptorType::STORAGE_BUFFER);
        let set = DescriptorSet::numbered(
            ctx,
            "occlusion culling",
            &[
                (OCC_CLUSTERS, sb),
                (OCC_VISIBLE, sb),
                (OCC_COMMANDS, sb),
                (OCC_COUNTERS, sb),
                (OCC_HIZ, Binding::one(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)),
            ],
        )?;
        set.write_buffer(ctx, OCC_CLUSTERS, c.clusters.raw);
        set.write_buffer(ctx, OCC_VISIBLE, c.visible.raw);
        set.write_buffer(ctx, OCC_COMMANDS, c.commands.raw);
        set.write_buffer(ctx, OCC_COUNTERS, c.counters.raw);
        let push = std::mem::size_of::<Push>() as u32;
        let cull_layout = pipeline_layout(ctx, "occlusion cull layout", &[scene_layout, set.layout], push)?;
        let spec = Specialization::new(&[]);
        let cull = compute_pipeline(ctx, "occlusion/cull.comp", cull_layout, &spec)?;
        let sampled = Binding::one(vk::DescriptorType::COMBINED_IMAGE_SAMPLER);
        let storage = Binding::one(vk::DescriptorType::STORAGE_IMAGE);
        let layout_of_levels =
            DescriptorSet::numbered(ctx, "depth pyramid layout", &[(HIZ_SRC, sampled), (HIZ_DST, storage)])?;
        let hiz_layout = pipeline_layout(ctx, "depth pyramid layout", &[layout_of_levels.layout], 0)?;
        let hiz = compute_pipeline(ctx, "occlusion/hiz.comp", hiz_layout, &spec)?;
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(vk::LOD_CLAMP_NONE);
        let sampler = unsafe { ctx.device.create_sampler(&info, None)? };
        ctx.name(sampler, "depth pyramid sampler");
        Ok(Occlusion {
            set,
            cull_layout,
            cull,
            hiz_layout,
            hiz,
            layout_of_levels,
            sampler,
            pyramid: RefCell::new(None),
        })
    }

    /// (Re)builds the pyramid for the depth target `depth` of `extent`.
    pub fn bind(&self, ctx: &Context, depth: vk::ImageView, extent: vk::Extent2D) -> Result<()> {
        if let Some(mut old) = self.pyramid.borrow_mut().take() {
            // The old pyramid may still be in use by a frame in flight.
            unsafe { ctx.device.device_wait_idle()? };
            old.destroy(ctx);
        }
        let p = Pyramid::new(ctx, depth, self.sampler, extent)?;
        self.set.write_image(ctx, OCC_HIZ, 0, p.image.view, self.sampler, vk::ImageLayout::GENERAL);
        *self.pyramid.borrow_mut() = Some(p);
        Ok(())
    }

    /// Records the cull pass of `phase` (1 or 2) with the barriers that make its results visible to the
    /// indirect draws (and, in phase 2, to the host's read of the counters).
    pub fn cull(&self, ctx: &Context, cmd: vk::CommandBuffer, gpu: &GpuScene, phase: u32) {
        let pyramid = self.pyramid.borrow();
        let Some(p) = pyramid.as_ref() else { return };
        let count = gpu.clusters.list.clusters.len() as u32;
        ctx.begin_label(
            cmd,
            if phase == 1 { "occlusion cull phase 1" } else { "occlusion cull phase 2" },
            [0.9, 0.5, 0.1, 1.0],
        );
        if phase == 1 {
            // The previous frame's draws and culls are done with the commands, visibility and pyramid.
            let reads = A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE | A::SHADER_SAMPLED_READ;
            memory_barrier(ctx, cmd, (S::ALL_COMMANDS, A::MEMORY_WRITE), (S::COMPUTE_SHADER, reads));
        }
        bind_compute(ctx, cmd, self.cull, self.cull_layout, &[gpu.set.set, self.set.set]);
        let push = Push {
            phase,
            count,
            levels: p.levels.len() as u32,
            width: p.extent.width,
            height: p.extent.height,
        };
        unsafe {
            ctx.device.cmd_push_constants(
                cmd,
                self.cull_layout,
                vk::ShaderStageFlags::ALL,
                0,
                bytemuck::bytes_of(&push),
            );
            ctx.device.cmd_dispatch(cmd, count.div_ceil(64), 1, 1);
        }
        let mut dst = (
            S::DRAW_INDIRECT | S::COMPUTE_SHADER,
            A::INDIRECT_COMMAND_READ | A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE,
        );
        if phase == 2 {
            dst = (dst.0 | S::HOST, dst.1 | A::HOST_READ);
        }
        memory_barrier(ctx, cmd, (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE), dst);
        ctx.end_label(cmd);
    }

    /// Records the pyramid of `depth` (left by phase 1 in
    /// DEPTH_ATTACHMENT_OPTIMAL, returned there for phase 2).
    pub fn pyramid(&self, ctx: &Context, cmd: vk::CommandBuffer, depth: vk::Image) {
        let pyramid = self.pyramid.borrow();
        let Some(p) = pyramid.as_ref() else { return };
        ctx.begin_label(cmd, "depth pyramid", [0.5, 0.5, 0.9, 1.0]);
        let tests = (
            S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
        );
        let aspect = vk::ImageAspectFlags::DEPTH;
        let (att, read) =
            (vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        let sampled = (S::COMPUTE_SHADER, A::SHADER_SAMPLED_READ);
        image_barrier(
            ctx,
            cmd,
            depth,
            aspect,
            att,
            read,
            (tests.0, A::DEPTH_STENCIL_ATTACHMENT_WRITE),
            sampled,
        );
        let mut extent = vk::Extent2D {
            width: p.extent.width.div_ceil(2).max(1),
            height: p.extent.height.div_ceil(2).max(1),
        };
        for set in &p.sets {
            bind_compute(ctx, cmd, self.hiz, self.hiz_layout, &[set.set]);
            unsafe { ctx.device.cmd_dispatch(cmd, extent.width.div_ceil(8), extent.height.div_ceil(8), 1) };
            // The next level (or phase 2's cull) reads this one.
            memory_barrier(ctx, cmd, (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE), sampled);
            extent = vk::Extent2D {
                width: extent.width.div_ceil(2).max(1),
                height: extent.height.div_ceil(2).max(1),
            };
        }
        image_barrier(ctx, cmd, depth, aspect, read, att, (S::COMPUTE_SHADER, A::NONE), tests);
        ctx.end_label(cmd);
    }

    /// The byte offset of `first` cluster's command in `phase`'s draws.
    pub fn command_offset(gpu: &GpuScene, phase: u32, first: u32) -> u64 {
        let base = if phase == 1 { 0 } else { gpu.clusters.list.clusters.len() as u64 };
        (base + first as u64) * COMMAND_STRIDE as u64
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if let Some(mut p) = self.pyramid.borrow_mut().take() {
            p.destroy(ctx);
        }
        self.set.destroy(ctx);
        self.layout_of_levels.destroy(ctx);
        unsafe {
            ctx.device.destroy_pipeline(self.cull, None);
            ctx.device.destroy_pipeline(self.hiz, None);
            ctx.device.destroy_pipeline_layout(self.cull_layout, None);
            ctx.device.destroy_pipeline_layout(self.hiz_layout, None);
            ctx.device.destroy_sampler(self.sampler, None);
        }
    }
}

crate::destroy_by_method!(Pyramid);
