//! Shadow maps of the budget's raster fallback (`Fallback::Raster`): one depth layer per light (layer
//! i is light i, so shaders index both alike), rendered for shadow-casting directional and spot lights
//! and PCF-sampled (glsl/common/shadow_map.glsl) where a pixel's shadow bit is off. Point lights stay
//! unshadowed: a cube map each would be six more passes.
//!
//! Per light, `SCENE_SHADOW_VIEWS` holds a `ShadowView` (scalar layout): view-projection (depth 0
//! near .. 1 far), world size of a texel at unit distance (perspective) or anywhere (orthographic),
//! 1 for perspective, two pad floats.

use anyhow::Result;
use ash::vk;
use glam::{Mat4, Vec3};
use gpu_allocator::MemoryLocation;

use super::origin::RenderOrigin;
use super::shared::SHADOW_MAP_SIZE;
use crate::scene::{Aabb, LightKind, Scene};
use crate::vk::frame_ring::{upload_now, Uploads};
use crate::vk::{image_barrier, Buffer, Context, Image};

/// Floats per light in the views buffer (mat4, texel, perspective, 2 pad).
pub const VIEW_FLOATS: usize = 20;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct ShadowMaps {
    /// The depth array, SHADER_READ_ONLY_OPTIMAL between frames.
    pub image: Image,
    /// One view per layer, the `shadow_map` pass's depth attachments.
    pub layer_views: Vec<vk::ImageView>,
    pub sampler: vk::Sampler,
    pub views: Buffer,
    /// Texels per side (1 when no light needs a map).
    pub size: u32,
    /// The lights (= layers) that get a map.
    pub mapped: Vec<u32>,
}

/// Whether `light` gets a shadow map in the fallback.
pub fn mapped(light: &crate::scene::Light) -> bool {
    light.casts_shadows && !matches!(light.kind, LightKind::Point)
}

impl ShadowMaps {
    pub fn null() -> ShadowMaps {
        ShadowMaps {
            image: Image::null(),
            layer_views: Vec::new(),
            sampler: vk::Sampler::null(),
            views: Buffer::null(),
            size: 0,
            mapped: Vec::new(),
        }
    }

    /// SHADOW_MAP_SIZE² per light when some directional or spot light casts shadows, else one texel (the
    /// descriptor stays valid).
    pub fn create(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        self.mapped = (0..scene.lights.len() as u32).filter(|&i| mapped(&scene.lights[i as usize])).collect();
        let any = !self.mapped.is_empty();
        let layers = scene.lights.len().max(1) as u32;
        self.size = if any { SHADOW_MAP_SIZE } else { 1 };
        let extent = vk::Extent2D { width: self.size, height: self.size };
        let usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        self.image = Image::new_2d_array(ctx, "shadow maps", DEPTH_FORMAT, extent, layers, usage)?;
        for layer in 0..layers {
            let info = vk::ImageViewCreateInfo::default()
                .image(self.image.raw)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(DEPTH_FORMAT)
                .subresource_range(
                    vk::ImageSubresourceRange::default()
                        .aspect_mask(vk::ImageAspectFlags::DEPTH)
                        .base_array_layer(layer)
                        .level_count(1)
                        .layer_count(1),
                );
            let view = unsafe { ctx.device.create_image_view(&info, None)? };
            ctx.name(view, &format!("shadow map layer {layer}"));
            self.layer_views.push(view);
        }
        // Hardware 2x2 PCF: a comparison sampler with linear filtering.
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_BORDER)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_BORDER)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .border_color(vk::BorderColor::FLOAT_OPAQUE_WHITE)
            .compare_enable(true)
            .compare_op(vk::CompareOp::LESS_OR_EQUAL)
            .max_lod(0.0);
        self.sampler = unsafe { ctx.device.create_sampler(&info, None)? };
        ctx.name(self.sampler, "shadow map comparison sampler");
        let bytes = (layers as usize * VIEW_FLOATS * 4) as u64;
        self.views = Buffer::new(
            ctx,
            "shadow map views",
            bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        upload_now(ctx, "shadow map views", |up| up.write(&self.views, 0, &vec![0u8; bytes as usize]))?;
        // Readable before the first render: every shader that binds it
        // declares it SHADER_READ_ONLY_OPTIMAL (depth 1 = nothing occludes).
        let img = self.image.raw;
        ctx.one_shot("shadow maps init", |cmd| {
            image_barrier(
                ctx,
                cmd,
                img,
                vk::ImageAspectFlags::DEPTH,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
                (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::SHADER_SAMPLED_READ),
            );
            Ok(())
        })
    }

    /// Fits each mapped light's view to the scene bounds (relative to `origin`) and writes the views
    /// through the frame's ring slot.
    pub fn write_views(&self, up: &mut Uploads, scene: &Scene, origin: RenderOrigin) -> Result<()> {
        let bounds = scene_bounds(scene);
        if bounds.is_empty() || self.size <= 1 {
            return Ok(());
        }
        let min = origin.point(bounds.min.as_dvec3());
        let max = origin.point(bounds.max.as_dvec3());
        let (centre, radius) = ((min + max) * 0.5, ((max - min).length() * 0.5).max(1e-3));
        let mut floats = vec![0f32; scene.lights.len().max(1) * VIEW_FLOATS];
        for (i, l) in scene.lights.iter().enumerate().filter(|(_, l)| mapped(l)) {
            let dir = l.direction.normalize_or(Vec3::NEG_Y);
            let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
            let (view_proj, texel, perspective) = match l.kind {
                LightKind::Spot { outer_cone, .. } => {
                    let eye = origin.point(l.position);
                    let far = l.range.unwrap_or(f32::INFINITY).min(eye.distance(centre) + radius).max(1e-2);
                    let near = (far * 1e-4).max(1e-3);
                    let fov = (2.0 * outer_cone).clamp(1e-3, 170f32.to_radians());
                    let proj = Mat4::perspective_rh(fov, 1.0, near, far);
                    let texel = 2.0 * (0.5 * fov).tan() / self.size as f32;
                    (proj * Mat4::look_at_rh(eye, eye + dir, up), texel, 1.0)
                }
                _ => {
                    // A bounding sphere, so the fit does not change as the light
                    // turns (visible bounds would be sharper in large scenes).
                    let eye = centre - dir * 2.0 * radius;
                    let proj = Mat4::orthographic_rh(-radius, radius, -radius, radius, radius, 3.0 * radius);
                    (proj * Mat4::look_at_rh(eye, centre, up), 2.0 * radius / self.size as f32, 0.0)
                }
            };
            let v = &mut floats[i * VIEW_FLOATS..(i + 1) * VIEW_FLOATS];
            v[..16].copy_from_slice(&view_proj.to_cols_array());
            (v[16], v[17]) = (texel, perspective);
        }
        up.write(&self.views, 0, bytemuck::cast_slice(&floats))
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            for v in self.layer_views.drain(..) {
                ctx.device.destroy_image_view(v, None);
            }
            ctx.device.destroy_sampler(self.sampler, None);
        }
        self.sampler = vk::Sampler::null();
        self.image.destroy(ctx);
        self.views.destroy(ctx);
    }
}

/// World bounds of every instance.
fn scene_bounds(scene: &Scene) -> Aabb {
    let mut b = Aabb::EMPTY;
    for inst in &scene.instances {
        let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
        b = b.union(&prim.bounds.transformed_f64(&inst.world));
    }
    b
}
