//! Pass `shadow_map`: the budget's raster shadow fallback (`--fallback raster`): depth from each
//! shadow-casting directional (orthographic, fitted to the scene) and spot light (perspective over its
//! cone) into its layer of gpu/shadow_map.rs's maps. Recorded only in frames where some visible
//! object's shadows are left out (`Renderer::record_with`).
//!
//! Bias: slope-scaled SLOPE_BIAS (in units of the depth change across a texel), no constant bias (in
//! D32_SFLOAT it would scale with depth's exponent), plus the lookup's normal offset
//! (glsl/common/shadow_map.glsl). 2 was the smallest slope factor without acne on the test plane at
//! 60° incidence.

use anyhow::Result;
use ash::vk;

use super::{Creation, Pass, PassDesc, Recording};
use crate::gpu::shadow_map::DEPTH_FORMAT;
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::shading::ShadingConfig;
use crate::render::targets::Targets;
use crate::vk::pipeline::pipeline_layout;
use crate::vk::raster::RasterPipeline;
use crate::vk::{image_barrier, Context};

const SLOPE_BIAS: f32 = 2.0;

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    (!c.shadow_fallback).then_some(
        "no shadow fallback: no --budget with --fallback raster, shadows or directional/spot shadow casters",
    )
}

pub const PASS: PassDesc = PassDesc {
    name: crate::render::budget::effects::SHADOW_MAP_PASS,
    this_frame: |f| f.shadow_maps_left_out,
    skip,
    // The shadow maps are the pass's own (transitions inside `record`).
    uses: |_, _| vec![Use::buffer(SharedBuffer::Geometry, Access::VertexInput)],
    create: |i: &Creation| Ok(Box::new(ShadowMapPass::new(i)?)),
};

pub struct ShadowMapPass {
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

impl ShadowMapPass {
    fn new(i: &Creation) -> Result<ShadowMapPass> {
        let layout = pipeline_layout(i.ctx, "shadow_map layout", &[i.gpu.set.layout], 4)?;
        let pipeline = create_pipeline(i.ctx, layout)
            .inspect_err(|_| unsafe { i.ctx.device.destroy_pipeline_layout(layout, None) })?;
        Ok(ShadowMapPass { layout, pipeline })
    }
}

impl Pass for ShadowMapPass {
    fn stage(&self) -> vk::PipelineStageFlags2 {
        vk::PipelineStageFlags2::VERTEX_SHADER
    }

    fn record(&self, cx: &Recording, cmd: vk::CommandBuffer) {
        let (ctx, d, scene) = (cx.ctx, &cx.ctx.device, cx.gpu);
        let maps = &scene.shadow;
        let depth_stages =
            vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS;
        let depth_access = vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE;
        // Earlier frames' lookups are done before the layers are cleared.
        image_barrier(
            ctx,
            cmd,
            maps.image.raw,
            vk::ImageAspectFlags::DEPTH,
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::NONE),
            (depth_stages, depth_access),
        );
        let extent = vk::Extent2D { width: maps.size, height: maps.size };
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        for &light in &maps.mapped {
            let depth = vk::RenderingAttachmentInfo::default()
                .image_view(maps.layer_views[light as usize])
                .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue {
                    depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 },
                });
            let info = vk::RenderingInfo::default().render_area(area).layer_count(1).depth_attachment(&depth);
            unsafe {
                d.cmd_begin_rendering(cmd, &info);
                let (w, h) = (extent.width as f32, extent.height as f32);
                let viewport =
                    vk::Viewport { x: 0.0, y: 0.0, width: w, height: h, min_depth: 0.0, max_depth: 1.0 };
                d.cmd_set_viewport(cmd, 0, &[viewport]);
                d.cmd_set_scissor(cmd, 0, &[area]);
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
                d.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.layout,
                    0,
                    &[scene.set.set],
                    &[],
                );
                d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::ALL, 0, &light.to_le_bytes());
                d.cmd_bind_index_buffer(cmd, scene.indices.raw, 0, vk::IndexType::UINT32);
                // Alpha-masked materials cast their whole surface's shadow
                // here (no alpha test in a depth-only pass).
                for draw in &scene.draws {
                    d.cmd_draw_indexed(
                        cmd,
                        draw.range.index_count,
                        1,
                        draw.range.first_index,
                        draw.range.vertex_offset as i32,
                        draw.instance,
                    );
                }
                d.cmd_end_rendering(cmd);
            }
        }
        // For the lookups in this frame's `direct` (and later frames').
        image_barrier(
            ctx,
            cmd,
            maps.image.raw,
            vk::ImageAspectFlags::DEPTH,
            vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            (depth_stages, vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE),
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::SHADER_SAMPLED_READ),
        );
    }

    fn bind(&self, _: &Context, _: &Targets) {}

    fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_pipeline(self.pipeline, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}

fn create_pipeline(ctx: &Context, layout: vk::PipelineLayout) -> Result<vk::Pipeline> {
    RasterPipeline {
        name: "shadow_map depth",
        vertex: "shadow_map.vert",
        fragment: None,
        color_formats: &[],
        depth_format: DEPTH_FORMAT,
        depth_compare: vk::CompareOp::LESS,
        // Both faces: a one-sided plane casts a shadow too.
        cull: Some(vk::CullModeFlags::NONE),
        slope_bias: Some(SLOPE_BIAS),
    }
    .create(ctx, layout)
}
