//! The scene on the GPU: ONE copy of vertex/index data (read by the
//! rasterizer, the acceleration-structure builds and the compute tracer),
//! materials, instances, lights, textures and the environment map, all bound
//! as descriptor set 0.

use anyhow::{Context as _, Result};
use ash::vk;
use glam::{Mat4, Vec3};
use gpu_allocator::MemoryLocation;

pub use super::draw::{Draw, PrimitiveRange};
use super::environment::upload_environment;
use super::memory::SceneMemory;
use super::origin::RenderOrigin;
use super::shadow_map::ShadowMaps;
use super::shared::{
    BUDGET_STAT_WORDS, RAY_COUNTER_SLOTS, SCENE_BUDGET_MASK, SCENE_BUDGET_STATS, SCENE_DFG, SCENE_EMITTERS,
    SCENE_ENV_CDF, SCENE_ENV_MAP, SCENE_ENV_SPECULAR, SCENE_EXPOSURE, SCENE_FRAME, SCENE_INDICES,
    SCENE_INSTANCES, SCENE_LIGHTS, SCENE_MATERIALS, SCENE_PRT, SCENE_RAY_COUNTERS, SCENE_SHADOW_MAPS,
    SCENE_SHADOW_VIEWS, SCENE_TEXTURES, SCENE_VERTICES,
};
use super::types::*;
use crate::scene::tangents::bounds_of;
use crate::scene::{Aabb, Filter, Instance, LightKind, SamplerDesc, Scene, Wrap};
use crate::vk::frame_ring::{upload_now, Uploads};
use crate::vk::memory::TextureDesc;
use crate::vk::pipeline::{Binding, DescriptorSet};
use crate::vk::{built, Buffer, Context, Image};

/// Written by the GPU and the frame ring, read through ring downloads.
const TRANSFER_BOTH: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::TRANSFER_SRC.as_raw() | vk::BufferUsageFlags::TRANSFER_DST.as_raw(),
);

pub struct GpuScene {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub materials: Buffer,
    /// Instances, lights and frame uniforms: device-local, written through
    /// the frame ring (vk/frame_ring.rs) like every per-frame host write.
    pub instances: Buffer,
    pub lights: Buffer,
    pub frame: Buffer,
    /// Frame counters (RAY_COUNTER_*: rays by kind, truncated pixels, bad
    /// pixels), reset and read back through the frame ring.
    pub ray_counters: Buffer,
    /// Auto-exposure state kept across frames, then the luminance
    /// reduction's scratch (render/tone.rs), read back through the ring.
    pub exposure: Buffer,
    /// The budget's per-object statistics (written by `heuristic`, read back through the ring) and
    /// selection (written by the host through the ring): BUDGET_STAT_WORDS + 1 words per object.
    pub budget_stats: Buffer,
    pub budget_mask: Buffer,
    /// Diffuse PRT transfer (prt/pack.rs), or its 4-word placeholder.
    pub prt: Buffer,
    pub textures: Vec<Image>,
    samplers: Vec<(SamplerDesc, vk::Sampler)>,
    pub env_map: Image,
    env_sampler: vk::Sampler,
    /// The map prefiltered by GGX roughness (gpu/env_prefilter.rs) and its trilinear sampler.
    pub env_specular: Image,
    env_specular_sampler: vk::Sampler,
    /// The split-sum table (gpu/split_sum.rs) and its clamped bilinear sampler.
    pub dfg: Image,
    dfg_sampler: vk::Sampler,
    /// The map's importance-sampling table for the path tracer
    /// (gpu/env_sampling.rs), or its header alone.
    pub env_cdf: Buffer,
    /// The emissive triangles as lights for the path tracer (gpu/emitters.rs).
    pub emitters: Buffer,
    /// The budget's raster shadow fallback (gpu/shadow_map.rs).
    pub shadow: ShadowMaps,
    pub set: DescriptorSet,
    /// Indexed by mesh, then primitive.
    pub ranges: Vec<Vec<PrimitiveRange>>,
    /// Deformed vertex range of each skinned instance (by `Instance::skinned`
    /// slot): written by the skinning pass, read by everything else.
    pub skinned: Vec<PrimitiveRange>,
    /// Bounds of each skinned slot's first pose (posed on the CPU).
    pub skinned_bounds: Vec<Aabb>,
    pub draws: Vec<Draw>,
    /// The draws' clusters for occlusion culling (gpu/clusters.rs): built
    /// by `ensure_clusters` when a frame first culls (none before).
    pub clusters: super::clusters::Clusters,
    pub light_count: u32,
    /// Mean environment radiance (solid-angle weighted), for the ambient term.
    pub env_mean: Vec3,
    /// The map's SH radiance coefficients (gpu/env_sh.rs); None without a map.
    pub env_sh: Option<crate::scene::sh::ShCoeffs>,
    /// What the GPU's world coordinates are relative to (see origin.rs).
    pub origin: RenderOrigin,
}

impl GpuScene {
    pub fn upload(ctx: &Context, scene: &Scene) -> Result<GpuScene> {
        let t0 = std::time::Instant::now();
        crate::progress::stage("uploading the scene");
        // Everything created lands in `gs` at once, so a failure half-way destroys what exists: no leak.
        let gs = built(ctx, GpuScene::empty(), |gs| gs.fill(ctx, scene))?;
        log::info!(
            "uploaded scene: {} triangles, {} instances, {} materials, {} textures, {:.1} MiB GPU memory, {:.0} ms",
            scene.triangle_count(),
            scene.instances.len(),
            scene.materials.len(),
            scene.textures.len(),
            ctx.allocated_bytes() as f64 / (1024.0 * 1024.0),
            t0.elapsed().as_secs_f64() * 1e3
        );
        log::info!("{}", gs.memory().describe(scene.triangle_count()));
        Ok(gs)
    }

    /// The bytes the scene's resources use, by category (sizes asked for, not the allocator's blocks).
    pub fn memory(&self) -> SceneMemory {
        let image = |i: &Image| i.allocation.as_ref().map_or(0, |a| a.size());
        let other = [
            &self.materials,
            &self.instances,
            &self.lights,
            &self.frame,
            &self.ray_counters,
            &self.exposure,
            &self.budget_stats,
            &self.budget_mask,
            &self.emitters,
            &self.shadow.views,
        ];
        SceneMemory {
            vertices: self.vertices.size,
            indices: self.indices.size,
            textures: self.textures.iter().map(image).sum(),
            environment: image(&self.env_map)
                + image(&self.env_specular)
                + image(&self.dfg)
                + self.env_cdf.size,
            prt: self.prt.size,
            shadow_maps: image(&self.shadow.image),
            other: other.iter().map(|b| b.size).sum(),
        }
    }

    /// Owns nothing yet; `destroy` is a no-op on it.
    fn empty() -> GpuScene {
        GpuScene {
            vertices: Buffer::null(),
            indices: Buffer::null(),
            materials: Buffer::null(),
            instances: Buffer::null(),
            lights: Buffer::null(),
            frame: Buffer::null(),
            ray_counters: Buffer::null(),
            exposure: Buffer::null(),
            budget_stats: Buffer::null(),
            budget_mask: Buffer::null(),
            prt: Buffer::null(),
            textures: Vec::new(),
            samplers: Vec::new(),
            env_map: Image::null(),
            env_specular: Image::null(),
            env_specular_sampler: vk::Sampler::null(),
            dfg: Image::null(),
            dfg_sampler: vk::Sampler::null(),
            env_cdf: Buffer::null(),
            emitters: Buffer::null(),
            clusters: super::clusters::Clusters::null(),
            env_sampler: vk::Sampler::null(),
            shadow: ShadowMaps::null(),
            set: DescriptorSet::null(),
            ranges: Vec::new(),
            skinned: Vec::new(),
            skinned_bounds: Vec::new(),
            draws: Vec::new(),
            light_count: 0,
            env_mean: Vec3::ZERO,
            env_sh: None,
            origin: RenderOrigin::default(),
        }
    }

    fn fill(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        self.origin = RenderOrigin::for_scene(scene);
        if !self.origin.is_zero() {
            log::info!("scene far from the world origin: GPU coordinates are relative to {}", self.origin.0);
        }
        let (vertices, indices, ranges, skinned, skinned_bounds) = upload_geometry(ctx, scene)?;
        (self.vertices, self.indices) = (vertices, indices);
        (self.ranges, self.skinned, self.skinned_bounds) = (ranges, skinned, skinned_bounds);

        let max_dim = ctx.caps.limits.max_image_dimension_2d;
        let fitted: Vec<(vk::Extent2D, std::borrow::Cow<[u8]>)> =
            scene.textures.iter().map(|t| fit_texture(t, max_dim)).collect();
        let descs: Vec<TextureDesc> = scene
            .textures
            .iter()
            .zip(&fitted)
            .enumerate()
            .map(|(i, (t, (extent, texels)))| TextureDesc {
                name: format!("texture {i} '{}'", t.name),
                format: if t.srgb { vk::Format::R8G8B8A8_SRGB } else { vk::Format::R8G8B8A8_UNORM },
                extent: *extent,
                texels,
                mipmaps: t.sampler.mipmaps,
            })
            .collect();
        self.textures =
            Image::textures(ctx, &descs).with_context(|| format!("uploading {} textures", descs.len()))?;
        for t in &scene.textures {
            if !self.samplers.iter().any(|(d, _)| *d == t.sampler) {
                let sampler = create_sampler(ctx, &t.sampler)?;
                self.samplers.push((t.sampler, sampler));
            }
        }

        let materials: Vec<GpuMaterial> = scene.materials.iter().map(super::material::gpu_material).collect();
        self.materials = Buffer::with_data(
            ctx,
            "materials",
            bytemuck::cast_slice(&materials),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        self.instances = Buffer::new(
            ctx,
            "instances",
            (scene.instances.len().max(1) * std::mem::size_of::<GpuInstance>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        self.lights = Buffer::new(
            ctx,
            "lights",
            (scene.lights.len().max(1) * std::mem::size_of::<GpuLight>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        self.frame = Buffer::new(
            ctx,
            "frame uniforms",
            std::mem::size_of::<GpuFrame>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        self.ray_counters = Buffer::new(
            ctx,
            "ray counters",
            RAY_COUNTER_SLOTS as u64 * 4,
            vk::BufferUsageFlags::STORAGE_BUFFER | TRANSFER_BOTH,
            MemoryLocation::GpuOnly,
        )?;
        self.exposure = Buffer::new(
            ctx,
            "exposure state",
            exposure_buffer_bytes(),
            vk::BufferUsageFlags::STORAGE_BUFFER | TRANSFER_BOTH,
            MemoryLocation::GpuOnly,
        )?;
        let objects = scene.objects.len().max(1) as u64;
        self.budget_stats = Buffer::new(
            ctx,
            "budget statistics",
            objects * BUDGET_STAT_WORDS as u64 * 4,
            vk::BufferUsageFlags::STORAGE_BUFFER | TRANSFER_BOTH,
            MemoryLocation::GpuOnly,
        )?;
        self.budget_mask = Buffer::new(
            ctx,
            "budget selection",
            objects * 4,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        self.prt = super::prt_buffer::placeholder(ctx)?;
        // No history yet (`valid` 0): the first measured frame converges at once.
        upload_now(ctx, "exposure state", |up| up.write(&self.exposure, 0, &[0u8; EXPOSURE_STATE_BYTES]))?;
        let env = upload_environment(ctx, scene)?;
        (self.env_map, self.env_specular, self.env_mean, self.env_sh) =
            (env.map, env.specular, env.mean, env.sh);
        self.dfg = super::split_sum::upload(ctx)?;
        self.env_cdf = super::env_sampling::upload(ctx, scene)?;
        self.emitters = super::emitters::upload(ctx, scene)?;
        self.shadow.create(ctx, scene)?;
        self.env_sampler = create_sampler(
            ctx,
            &SamplerDesc {
                mag_filter: Filter::Linear,
                min_filter: Filter::Linear,
                mipmaps: false,
                wrap_u: Wrap::Repeat,
                wrap_v: Wrap::ClampToEdge,
            },
        )?;
        self.env_specular_sampler = create_sampler(
            ctx,
            &SamplerDesc {
                mag_filter: Filter::Linear,
                min_filter: Filter::Linear,
                mipmaps: true,
                wrap_u: Wrap::Repeat,
                wrap_v: Wrap::ClampToEdge,
            },
        )?;
        self.dfg_sampler = create_sampler(
            ctx,
            &SamplerDesc {
                mag_filter: Filter::Linear,
                min_filter: Filter::Linear,
                mipmaps: false,
                wrap_u: Wrap::ClampToEdge,
                wrap_v: Wrap::ClampToEdge,
            },
        )?;

        let sampled = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        // In binding order (shared_values.rs: SCENE_*), checked below.
        let layout = [
            (SCENE_FRAME, Binding::one(vk::DescriptorType::UNIFORM_BUFFER)),
            (SCENE_VERTICES, Binding::one(storage)),
            (SCENE_INDICES, Binding::one(storage)),
            (SCENE_MATERIALS, Binding::one(storage)),
            (SCENE_INSTANCES, Binding::one(storage)),
            (SCENE_LIGHTS, Binding::one(storage)),
            (SCENE_ENV_MAP, Binding::one(sampled)),
            (SCENE_RAY_COUNTERS, Binding::one(storage)),
            (SCENE_EXPOSURE, Binding::one(storage)),
            (SCENE_BUDGET_STATS, Binding::one(storage)),
            (SCENE_BUDGET_MASK, Binding::one(storage)),
            (SCENE_SHADOW_MAPS, Binding::one(sampled)),
            (SCENE_SHADOW_VIEWS, Binding::one(storage)),
            (SCENE_PRT, Binding::one(storage)),
            (SCENE_ENV_CDF, Binding::one(storage)),
            (SCENE_EMITTERS, Binding::one(storage)),
            (SCENE_ENV_SPECULAR, Binding::one(sampled)),
            (SCENE_DFG, Binding::one(sampled)),
            // Bindless textures: variable-count, so the last binding.
            (
                SCENE_TEXTURES,
                Binding { ty: sampled, count: self.textures.len().max(1) as u32, bindless: true },
            ),
        ];
        debug_assert!(layout.iter().enumerate().all(|(i, (b, _))| i as u32 == *b));
        let bindings: Vec<Binding> = layout.iter().map(|(_, b)| *b).collect();
        self.set = DescriptorSet::new(ctx, "scene set", &bindings)?;
        let set = &self.set;
        set.write_buffer(ctx, SCENE_FRAME, self.frame.raw);
        set.write_buffer(ctx, SCENE_VERTICES, self.vertices.raw);
        set.write_buffer(ctx, SCENE_INDICES, self.indices.raw);
        set.write_buffer(ctx, SCENE_MATERIALS, self.materials.raw);
        set.write_buffer(ctx, SCENE_INSTANCES, self.instances.raw);
        set.write_buffer(ctx, SCENE_LIGHTS, self.lights.raw);
        set.write_buffer(ctx, SCENE_RAY_COUNTERS, self.ray_counters.raw);
        set.write_buffer(ctx, SCENE_EXPOSURE, self.exposure.raw);
        set.write_buffer(ctx, SCENE_BUDGET_STATS, self.budget_stats.raw);
        set.write_buffer(ctx, SCENE_BUDGET_MASK, self.budget_mask.raw);
        set.write_buffer(ctx, SCENE_SHADOW_VIEWS, self.shadow.views.raw);
        set.write_buffer(ctx, SCENE_PRT, self.prt.raw);
        set.write_buffer(ctx, SCENE_ENV_CDF, self.env_cdf.raw);
        set.write_buffer(ctx, SCENE_EMITTERS, self.emitters.raw);
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        set.write_image(ctx, SCENE_ENV_MAP, 0, self.env_map.view, self.env_sampler, read);
        set.write_image(ctx, SCENE_ENV_SPECULAR, 0, self.env_specular.view, self.env_specular_sampler, read);
        set.write_image(ctx, SCENE_DFG, 0, self.dfg.view, self.dfg_sampler, read);
        set.write_image(ctx, SCENE_SHADOW_MAPS, 0, self.shadow.image.view, self.shadow.sampler, read);
        for (i, (img, tex)) in self.textures.iter().zip(&scene.textures).enumerate() {
            let s = self.samplers.iter().find(|(d, _)| *d == tex.sampler).map(|(_, s)| *s).unwrap();
            set.write_image(ctx, SCENE_TEXTURES, i as u32, img.view, s, read);
        }

        self.draws = build_draws(scene, &self.ranges, &self.skinned);
        self.light_count = scene.lights.len() as u32;
        upload_now(ctx, "instances and lights", |up| self.update_dynamic(up, scene))
    }

    /// Re-writes instance transforms and lights (animation, later issues)
    /// through the frame's ring slot.
    pub fn update_dynamic(&self, up: &mut Uploads, scene: &Scene) -> Result<()> {
        write_instances(up, scene, self.origin, &self.ranges, &self.skinned, &self.instances)?;
        write_lights(up, scene, self.origin, &self.lights)
    }

    /// Where `inst`'s vertices live: its own deformed range when skinned.
    pub fn instance_range(&self, inst: &Instance) -> PrimitiveRange {
        instance_range(&self.ranges, &self.skinned, inst)
    }

    pub fn write_frame(&self, up: &mut Uploads, frame: &GpuFrame) -> Result<()> {
        up.write(&self.frame, 0, bytemuck::bytes_of(frame))
    }

    /// Replaces the PRT buffer (`words`: prt/pack.rs `pack`; None: the
    /// placeholder). Waits for the device: the scene set is rewritten.
    pub fn set_prt(&mut self, ctx: &Context, words: Option<&[u32]>) -> Result<()> {
        unsafe { ctx.device.device_wait_idle() }
            .context("vkDeviceWaitIdle before replacing the PRT buffer")?;
        let new = match words {
            Some(w) => Buffer::with_data(
                ctx,
                "prt transfer",
                bytemuck::cast_slice(w),
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?,
            None => super::prt_buffer::placeholder(ctx)?,
        };
        let mut old = std::mem::replace(&mut self.prt, new);
        old.destroy(ctx);
        self.set.write_buffer(ctx, SCENE_PRT, self.prt.raw);
        Ok(())
    }

    /// Builds and uploads the draws' clusters unless they exist: only
    /// occlusion culling (off by default) reads them, so a scene that is
    /// never culled pays neither the build nor the buffers.
    pub fn ensure_clusters(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        if self.clusters.clusters.raw == vk::Buffer::null() {
            self.clusters = super::clusters::Clusters::upload(ctx, scene, &self.draws)?;
        }
        Ok(())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for b in [
            &mut self.vertices,
            &mut self.indices,
            &mut self.materials,
            &mut self.instances,
            &mut self.lights,
            &mut self.frame,
            &mut self.ray_counters,
            &mut self.exposure,
            &mut self.budget_stats,
            &mut self.budget_mask,
            &mut self.prt,
        ] {
            b.destroy(ctx);
        }
        for t in &mut self.textures {
            t.destroy(ctx);
        }
        self.env_map.destroy(ctx);
        self.env_specular.destroy(ctx);
        self.dfg.destroy(ctx);
        self.env_cdf.destroy(ctx);
        self.emitters.destroy(ctx);
        self.shadow.destroy(ctx);
        self.clusters.destroy(ctx);
        unsafe {
            for (_, s) in &self.samplers {
                ctx.device.destroy_sampler(*s, None);
            }
            ctx.device.destroy_sampler(self.env_sampler, None);
            ctx.device.destroy_sampler(self.env_specular_sampler, None);
            ctx.device.destroy_sampler(self.dfg_sampler, None);
        }
        self.set.destroy(ctx);
    }
}

fn instance_range(
    ranges: &[Vec<PrimitiveRange>],
    skinned: &[PrimitiveRange],
    inst: &Instance,
) -> PrimitiveRange {
    match inst.skinned {
        Some(slot) => skinned[slot],
        None => ranges[inst.mesh][inst.primitive],
    }
}

type Geometry = (Buffer, Buffer, Vec<Vec<PrimitiveRange>>, Vec<PrimitiveRange>, Vec<Aabb>);

/// One vertex and one index buffer for all primitives, plus one deformed copy per skinned instance
/// (posed on the CPU for the first frame; the skinning pass rewrites it from then on).
fn upload_geometry(ctx: &Context, scene: &Scene) -> Result<Geometry> {
    let mut vertex_data = Vec::new();
    let mut index_data: Vec<u32> = Vec::new();
    let mut ranges = Vec::with_capacity(scene.meshes.len());
    for mesh in &scene.meshes {
        let mut r = Vec::with_capacity(mesh.primitives.len());
        for p in &mesh.primitives {
            r.push(PrimitiveRange {
                first_index: index_data.len() as u32,
                index_count: p.indices.len() as u32,
                vertex_offset: vertex_data.len() as u32,
                vertex_count: p.vertices.len() as u32,
            });
            vertex_data.extend_from_slice(&p.vertices);
            index_data.extend_from_slice(&p.indices);
        }
        ranges.push(r);
    }
    let (mut skinned, mut skinned_bounds) = (Vec::new(), Vec::new());
    let world = scene.world_matrices();
    for inst in &scene.instances {
        let Some(posed) = scene.skinned_pose(inst, &world) else { continue };
        skinned.push(PrimitiveRange {
            vertex_offset: vertex_data.len() as u32,
            ..ranges[inst.mesh][inst.primitive]
        });
        skinned_bounds.push(bounds_of(&posed));
        vertex_data.extend(posed);
    }
    // The usage flags every consumer needs, so no second copy is ever made.
    let mut usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    if ctx.caps.buffer_device_address {
        // Acceleration-structure builds read the geometry by address.
        usage |= vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
    }
    if ctx.rt.acceleration_structure {
        usage |= vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR;
    }
    let mut vertices = Buffer::with_data(ctx, "scene vertices", bytemuck::cast_slice(&vertex_data), usage)?;
    let indices = Buffer::with_data(
        ctx,
        "scene indices",
        bytemuck::cast_slice(&index_data),
        usage | vk::BufferUsageFlags::INDEX_BUFFER,
    )
    .inspect_err(|_| vertices.destroy(ctx))?;
    Ok((vertices, indices, ranges, skinned, skinned_bounds))
}

fn build_draws(scene: &Scene, ranges: &[Vec<PrimitiveRange>], skinned: &[PrimitiveRange]) -> Vec<Draw> {
    scene
        .instances
        .iter()
        .enumerate()
        .map(|(i, inst)| {
            let m = &scene.materials[scene.instance_material(inst)];
            Draw {
                instance: i as u32,
                range: instance_range(ranges, skinned, inst),
                alpha_mode: m.alpha_mode,
                double_sided: m.double_sided,
            }
        })
        .collect()
}

/// Textures above maxImageDimension2D are downscaled (aspect kept, triangle filter) with a warning
/// rather than handed to the driver.
fn fit_texture(t: &crate::scene::Texture, max_dim: u32) -> (vk::Extent2D, std::borrow::Cow<'_, [u8]>) {
    let extent = vk::Extent2D { width: t.width, height: t.height };
    let largest = t.width.max(t.height);
    if largest <= max_dim || max_dim == 0 {
        return (extent, std::borrow::Cow::Borrowed(&t.rgba8));
    }
    let scale = max_dim as f64 / largest as f64;
    let (w, h) = (((t.width as f64 * scale) as u32).max(1), ((t.height as f64 * scale) as u32).max(1));
    log::warn!(
        "texture '{}': {}x{} exceeds this device's maxImageDimension2D ({max_dim}); downscaled to {w}x{h}",
        t.name,
        t.width,
        t.height
    );
    let Some(img) = image::RgbaImage::from_raw(t.width, t.height, t.rgba8.clone()) else {
        return (extent, std::borrow::Cow::Borrowed(&t.rgba8)); // loader guarantees the size
    };
    let small = image::imageops::resize(&img, w, h, image::imageops::FilterType::Triangle);
    (vk::Extent2D { width: w, height: h }, std::borrow::Cow::Owned(small.into_raw()))
}

fn write_instances(
    up: &mut Uploads,
    scene: &Scene,
    origin: RenderOrigin,
    ranges: &[Vec<PrimitiveRange>],
    skinned: &[PrimitiveRange],
    buf: &Buffer,
) -> Result<()> {
    let data: Vec<GpuInstance> = scene
        .instances
        .iter()
        .map(|inst| {
            let r = instance_range(ranges, skinned, inst);
            let props = &scene.objects.get(inst.object).map(|o| o.props.clone()).unwrap_or_default();
            let world = origin.matrix(&inst.world);
            let normal = normal_matrix(&world);
            GpuInstance {
                world: world.to_cols_array(),
                normal_matrix: normal.to_cols_array(),
                material: scene.instance_material(inst) as u32,
                first_index: r.first_index,
                vertex_offset: r.vertex_offset,
                object_id: inst.object as u32,
                index_count: r.index_count,
                flags: if props.casts_shadows { INST_CASTS_SHADOWS } else { 0 },
                pad: [0; 2],
            }
        })
        .collect();
    up.write(buf, 0, bytemuck::cast_slice(&data))
}

/// Inverse transpose of the upper 3x3; a singular matrix (zero scale) keeps
/// its own 3x3 rather than producing NaNs.
fn normal_matrix(world: &Mat4) -> Mat4 {
    let m3 = glam::Mat3::from_mat4(*world);
    let det = m3.determinant();
    let n = if det.abs() > f32::MIN_POSITIVE && det.is_finite() { m3.inverse().transpose() } else { m3 };
    Mat4::from_mat3(n)
}

fn write_lights(up: &mut Uploads, scene: &Scene, origin: RenderOrigin, buf: &Buffer) -> Result<()> {
    let data: Vec<GpuLight> = scene.lights.iter().map(|l| gpu_light(l, origin)).collect();
    up.write(buf, 0, bytemuck::cast_slice(&data))
}

fn gpu_light(l: &crate::scene::Light, origin: RenderOrigin) -> GpuLight {
    let (kind, spot_scale, spot_offset) = match l.kind {
        LightKind::Directional => (LIGHT_DIRECTIONAL, 0.0, 0.0),
        LightKind::Point => (LIGHT_POINT, 0.0, 0.0),
        LightKind::Spot { inner_cone, outer_cone } => {
            // KHR_lights_punctual's recommended smooth cone falloff.
            let cos_outer = outer_cone.cos();
            let cos_inner = inner_cone.cos();
            let scale = 1.0 / (cos_inner - cos_outer).max(1e-4);
            (LIGHT_SPOT, scale, -cos_outer * scale)
        }
    };
    GpuLight {
        position: origin.point(l.position).to_array(),
        kind,
        direction: l.direction.normalize_or(Vec3::NEG_Y).to_array(),
        range: l.range.unwrap_or(0.0),
        radiance: (l.color * l.intensity).to_array(),
        spot_scale,
        spot_offset,
        flags: if l.casts_shadows { LIGHT_CASTS_SHADOWS } else { 0 },
        pad: [0.0; 2],
    }
}

fn create_sampler(ctx: &Context, d: &SamplerDesc) -> Result<vk::Sampler> {
    let filter = |f: Filter| match f {
        Filter::Nearest => vk::Filter::NEAREST,
        Filter::Linear => vk::Filter::LINEAR,
    };
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => vk::SamplerAddressMode::REPEAT,
        Wrap::MirroredRepeat => vk::SamplerAddressMode::MIRRORED_REPEAT,
        Wrap::ClampToEdge => vk::SamplerAddressMode::CLAMP_TO_EDGE,
    };
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(filter(d.mag_filter))
        .min_filter(filter(d.min_filter))
        .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
        .address_mode_u(wrap(d.wrap_u))
        .address_mode_v(wrap(d.wrap_v))
        .address_mode_w(vk::SamplerAddressMode::REPEAT)
        .max_lod(if d.mipmaps { vk::LOD_CLAMP_NONE } else { 0.0 });
    let s = unsafe { ctx.device.create_sampler(&info, None)? };
    ctx.name(s, &format!("sampler {d:?}"));
    Ok(s)
}

crate::destroy_by_method!(GpuScene);
