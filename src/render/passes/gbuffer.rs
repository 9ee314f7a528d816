//! Pass `gbuffer`: rasterizes a visibility buffer, each pixel's (instance + 1, primitive), with
//! reversed-Z depth (clear 0, GREATER); `gbuffer_resolve` fills the material targets. No shading
//! attributes are interpolated: on llvmpipe that was most of this pass's time for many tiny triangles
//! (bench/results/lavapipe-2core-vm-raster.md). Alpha-masked materials get a pipeline with uv and
//! the alpha test; opaque ones keep early depth testing. Each instance is one non-indexed draw (or
//! one indirect draw per cluster with occlusion culling) with world matrix and index range as push
//! constants, so no stage reads gl_PrimitiveID or a per-vertex instance (both slow on llvmpipe;
//! glsl/common/gbuffer_draw.glsl).

use anyhow::Result;
use ash::vk;

use super::fullscreen::TargetBinding;
use super::{Creation, Pass, PassDesc, Recording};
use crate::gpu::clusters::COMMAND_STRIDE;
use crate::gpu::shared::{GB_ALBEDO, GB_HIT, GB_MATERIAL, GB_NORMAL};
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::occlusion::Occlusion;
use crate::render::shading::{Mode, ShadingConfig};
use crate::render::targets::{TargetDesc, Targets};
use crate::scene::AlphaMode;
use crate::vk::pipeline::{pipeline_layout, Specialization};
use crate::vk::raster::RasterPipeline;
use crate::vk::Context;

/// G-buffer targets (`gbuffer` + `gbuffer_resolve` in hybrid mode, `primary` in pure-RT mode).
/// Albedo is sRGB-encoded by the shaders into UNORM (glsl/common/srgb.glsl) so both modes store the
/// same bytes; the normal is octahedral in one uint; emission is not stored. 24 bytes a pixel with
/// depth, 20 in pure-RT mode.
pub static ALBEDO: TargetDesc = TargetDesc::new("gbuffer albedo+occlusion", vk::Format::R8G8B8A8_UNORM);
pub static NORMAL: TargetDesc = TargetDesc::new("gbuffer normal (octahedral)", vk::Format::R32_UINT);
pub static MATERIAL: TargetDesc =
    TargetDesc::new("gbuffer metallic+roughness+transmission", vk::Format::R8G8B8A8_UNORM);
pub static HIT: TargetDesc = TargetDesc::new("gbuffer hit (instance, primitive)", vk::Format::R32G32_UINT);
pub static DEPTH: TargetDesc = TargetDesc::new("gbuffer depth (reversed-Z)", vk::Format::D32_SFLOAT);

/// Every G-buffer target, for the bytes-per-pixel figure.
pub const ALL: [&TargetDesc; 5] = [&ALBEDO, &NORMAL, &MATERIAL, &HIT, &DEPTH];

/// Bytes per pixel of the G-buffer targets `t` holds (the primary-hit
/// target and the depth buffer included).
pub fn bytes_per_pixel(t: &Targets) -> u32 {
    ALL.iter().filter_map(|d| t.get(d)).map(|t| crate::render::targets::bytes_per_pixel(t.desc.format)).sum()
}

/// The set-1 bindings through which later passes read the primary hit.
pub fn reads() -> Vec<TargetBinding> {
    let s = Access::Sampled;
    vec![
        TargetBinding::new(GB_ALBEDO, &ALBEDO, s),
        TargetBinding::new(GB_NORMAL, &NORMAL, s),
        TargetBinding::new(GB_MATERIAL, &MATERIAL, s),
        TargetBinding::new(GB_HIT, &HIT, s),
    ]
}

fn uses(c: &ShadingConfig) -> Vec<Use> {
    let depth = Use::image(&DEPTH, Access::DepthAttachment);
    vec![
        Use::image(&HIT, Access::ColorAttachment),
        // Occlusion culling builds its pyramid from the depth (render/occlusion.rs).
        if c.occlusion { depth.sampled_within() } else { depth },
        Use::buffer(SharedBuffer::Geometry, Access::VertexInput),
    ]
}

fn skip(c: &ShadingConfig) -> Option<&'static str> {
    match (c.mode, c.visibility) {
        (Mode::Rt, _) => Some("pure ray-traced mode: camera rays (pass primary) find the primary hits"),
        (_, crate::render::settings::PrimaryVisibility::Traced) => {
            Some("--primary-visibility traced: pass visibility trace finds the primary hits")
        }
        _ => None,
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "gbuffer",
    this_frame: |f| {
        (f.visibility == Some(super::Technique::Traced)).then_some("traced visibility this frame")
    },
    skip,
    uses: |c, _| uses(c),
    create: |i: &Creation| {
        let mut p = GBufferPass::new(i.ctx, i.gpu.set.layout)?;
        if i.config.occlusion && !i.gpu.clusters.list.clusters.is_empty() {
            // The cluster draws use the whole draws' pipelines (gbuffer.vert).
            p.clusters = Some(Occlusion::new(i.ctx, i.gpu, i.gpu.set.layout)?);
            p.bind(i.ctx, i.targets);
        }
        Ok(Box::new(p))
    },
};

/// The push constants of a draw, whole or of clusters (glsl/common/gbuffer_draw.glsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GBufferDraw {
    /// The instance's world matrix (cull::FrameDraw::world), column-major.
    world: [f32; 16],
    instance: u32,
    first_index: u32,
    vertex_offset: i32,
}

pub struct GBufferPass {
    layout: vk::PipelineLayout,
    opaque: vk::Pipeline,
    masked: vk::Pipeline,
    /// Occlusion culling on (render/occlusion.rs): the culling that picks
    /// the clusters to draw.
    clusters: Option<Occlusion>,
}

impl GBufferPass {
    pub fn new(ctx: &Context, scene_layout: vk::DescriptorSetLayout) -> Result<GBufferPass> {
        let push = std::mem::size_of::<GBufferDraw>() as u32;
        let layout = pipeline_layout(ctx, "gbuffer layout", &[scene_layout], push)?;
        let opaque = create_pipeline(ctx, layout, false)?;
        let masked = create_pipeline(ctx, layout, true)?;
        Ok(GBufferPass { layout, opaque, masked, clusters: None })
    }

    /// Records the draws of `cx.draws`: whole (phase 0), or the clusters
    /// the cull pass picked for `phase` 1 or 2.
    fn draw(&self, cx: &Recording, cmd: vk::CommandBuffer, phase: u32) {
        let (d, scene) = (&cx.ctx.device, cx.gpu);
        let layout = self.layout;
        unsafe {
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                layout,
                0,
                &[scene.set.set],
                &[],
            );
            // Opaque first so masked geometry is depth-tested against it. Single-sided geometry is back-face
            // culled; a mirroring transform turns its front faces clockwise.
            for (pipeline, masked) in [(self.opaque, false), (self.masked, true)] {
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
                for fd in &cx.draws.draws {
                    let draw = &scene.draws[fd.draw as usize];
                    if (draw.alpha_mode != AlphaMode::Opaque) != masked {
                        continue;
                    }
                    let cull =
                        if draw.double_sided { vk::CullModeFlags::NONE } else { vk::CullModeFlags::BACK };
                    d.cmd_set_cull_mode(cmd, cull);
                    let front =
                        if fd.mirrored { vk::FrontFace::CLOCKWISE } else { vk::FrontFace::COUNTER_CLOCKWISE };
                    d.cmd_set_front_face(cmd, front);
                    let push = GBufferDraw {
                        world: fd.world.to_cols_array(),
                        instance: draw.instance,
                        first_index: draw.range.first_index,
                        vertex_offset: draw.range.vertex_offset as i32,
                    };
                    d.cmd_push_constants(
                        cmd,
                        layout,
                        vk::ShaderStageFlags::ALL,
                        0,
                        bytemuck::bytes_of(&push),
                    );
                    if phase == 0 {
                        // The instance is a push constant, not firstInstance.
                        d.cmd_draw(cmd, draw.range.index_count, 1, draw.range.first_index, 0);
                        continue;
                    }
                    // One indirect draw per cluster, from its first index;
                    // the cull pass set each one's instance count to 0 or 1.
                    let (first, count) = scene.clusters.list.ranges[fd.draw as usize];
                    let offset = Occlusion::command_offset(scene, phase, first);
                    d.cmd_draw_indirect(cmd, scene.clusters.commands.raw, offset, count, COMMAND_STRIDE);
                }
            }
        }
    }

    /// Begins rendering into the hit and depth targets, cleared or kept.
    fn begin(&self, cx: &Recording, cmd: vk::CommandBuffer, clear: bool) {
        let (d, t) = (&cx.ctx.device, cx.targets);
        let (Some(hit), Some(depth_target)) = (t.get(&HIT), t.get(&DEPTH)) else { return };
        let load = if clear { vk::AttachmentLoadOp::CLEAR } else { vk::AttachmentLoadOp::LOAD };
        // Hit id 0: the camera ray missed.
        let colors = [vk::RenderingAttachmentInfo::default()
            .image_view(hit.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { color: vk::ClearColorValue { uint32: [0; 4] } })];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(depth_target.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 },
            });
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: t.extent };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colors)
            .depth_attachment(&depth);
        unsafe {
            d.cmd_begin_rendering(cmd, &info);
            d.cmd_set_viewport(
                cmd,
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: t.extent.width as f32,
                    height: t.extent.height as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            d.cmd_set_scissor(cmd, 0, &[area]);
        }
    }
}

impl Pass for GBufferPass {
    fn stage(&self) -> vk::PipelineStageFlags2 {
        vk::PipelineStageFlags2::VERTEX_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER
    }

    fn record(&self, cx: &Recording, cmd: vk::CommandBuffer) {
        let (ctx, t) = (cx.ctx, cx.targets);
        let (Some(_), Some(depth)) = (t.get(&HIT), t.get(&DEPTH)) else { return };
        let d = &ctx.device;
        let Some(o) = &self.clusters else {
            self.begin(cx, cmd, true);
            self.draw(cx, cmd, 0);
            unsafe { d.cmd_end_rendering(cmd) };
            return;
        };
        o.cull(ctx, cmd, cx.gpu, 1);
        ctx.begin_label(cmd, "gbuffer phase 1 (visible last frame)", [0.2, 0.7, 0.2, 1.0]);
        self.begin(cx, cmd, true);
        self.draw(cx, cmd, 1);
        unsafe { d.cmd_end_rendering(cmd) };
        ctx.end_label(cmd);
        o.pyramid(ctx, cmd, depth.raw);
        o.cull(ctx, cmd, cx.gpu, 2);
        // Phase 2 loads the hits phase 1 wrote (the depth's barrier is the pyramid's).
        let color =
            (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
        let load =
            (color.0, vk::AccessFlags2::COLOR_ATTACHMENT_READ | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
        crate::vk::memory_barrier(ctx, cmd, color, load);
        ctx.begin_label(cmd, "gbuffer phase 2 (disoccluded)", [0.2, 0.7, 0.2, 1.0]);
        self.begin(cx, cmd, false);
        self.draw(cx, cmd, 2);
        unsafe { d.cmd_end_rendering(cmd) };
        ctx.end_label(cmd);
    }

    fn bind(&self, ctx: &Context, targets: &Targets) {
        if let (Some(o), Some(depth)) = (&self.clusters, targets.get(&DEPTH)) {
            // No error path in `bind`: a failed pyramid leaves culling off
            // for the frame (cull and pyramid record nothing without one).
            if let Err(e) = o.bind(ctx, depth.view, targets.extent) {
                log::error!("occlusion culling: depth pyramid: {e:#}");
            }
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_pipeline(self.opaque, None);
            ctx.device.destroy_pipeline(self.masked, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        if let Some(mut o) = self.clusters.take() {
            o.destroy(ctx);
        }
    }
}

fn create_pipeline(ctx: &Context, layout: vk::PipelineLayout, alpha_test: bool) -> Result<vk::Pipeline> {
    let spec = Specialization::new(&[]);
    let (name, vertex, fragment) = if alpha_test {
        ("gbuffer alpha-masked", "gbuffer_uv", "visibility_masked")
    } else {
        ("gbuffer opaque", "gbuffer.vert", "visibility.frag")
    };
    RasterPipeline {
        name,
        vertex,
        fragment: Some((fragment, &spec)),
        color_formats: &[HIT.format],
        depth_format: DEPTH.format,
        // Reversed Z.
        depth_compare: vk::CompareOp::GREATER,
        // Per draw: double-sided materials and mirroring transforms.
        cull: None,
        slope_bias: None,
    }
    .create(ctx, layout)
}
