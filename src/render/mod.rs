//! Frame orchestration. One frame reads top to bottom like the data flow in
//! DESIGN.md: G-buffer -> deferred lighting -> tone map (-> readback or present).

pub mod compute_pass;
pub mod gbuffer;
pub mod output;
pub mod shading;
pub mod skinning;
pub mod targets;

use anyhow::{Context as _, Result};
use ash::vk;
use glam::Mat4;
use gpu_allocator::MemoryLocation;

use crate::accel::compute_bvh::ComputeBvh;
use crate::accel::dynamic::{RebuildPolicy, Update};
use crate::accel::SceneAccel;
use crate::gpu::types::GpuFrame;
use crate::gpu::GpuScene;
use crate::scene::{Camera, Scene};
use crate::vk::pipeline::{Binding, DescriptorSet, Specialization};
use crate::vk::timer::{pass, GpuTimer};
use crate::vk::{image_barrier, Buffer, Context};
use compute_pass::{ComputePass, Input};
use gbuffer::GBufferPass;
use shading::{Backend, Effects, Mode, SceneNeeds, ShadingConfig};
use skinning::Skinning;
use targets::Targets;

/// G-buffer debug views (also selectable in the viewer).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum DebugView {
    #[default]
    None,
    Albedo,
    Normal,
    Depth,
    Material,
    Object,
}

impl DebugView {
    fn code(self) -> u32 {
        self as u32
    }
}

#[derive(Clone, Copy, Debug)]
pub struct RenderSettings {
    pub exposure: f32,
    pub debug_view: DebugView,
    pub mode: Mode,
    pub effects: Effects,
    pub backend: Backend,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            exposure: 1.0,
            debug_view: DebugView::None,
            mode: Mode::Hybrid,
            effects: Effects::default(),
            backend: Backend::Auto,
        }
    }
}

/// What a headless frame gives back.
pub struct FrameOutput {
    pub width: u32,
    pub height: u32,
    /// Tone-mapped sRGB, RGBA8, row-major, top row first.
    pub ldr: Vec<u8>,
    /// Linear radiance, RGBA32F.
    pub hdr: Vec<f32>,
    /// GPU milliseconds per pass.
    pub timings: Vec<(&'static str, f64)>,
    /// Rays traced by kind (camera, shadow, secondary) when
    /// `Effects::count_rays` is on, else zeros.
    pub ray_counts: [u32; 3],
}

/// What one scene update refits or rebuilds, decided on the host before
/// its commands are recorded.
struct UpdatePlan {
    blas: Vec<Update>,
    bvh: Vec<Update>,
}

pub struct Renderer {
    pub gpu: GpuScene,
    pub targets: Targets,
    gbuffer: GBufferPass,
    /// The shading/integrator pass and the variant it was built for.
    shading: Option<(ShadingConfig, ComputePass)>,
    tonemap: ComputePass,
    needs: SceneNeeds,
    /// Built on first use by a tracing variant.
    accel: Option<(SceneAccel, DescriptorSet)>,
    /// The compute backend's BVH, built on first use.
    bvh: Option<ComputeBvh>,
    pub timer: GpuTimer,
    cmd: vk::CommandBuffer,
    /// Skinning of skinned instances, if the scene has any.
    skinning: Option<Skinning>,
    /// When skinned acceleration structures are rebuilt instead of refit.
    pub rebuild_policy: RebuildPolicy,
    update_cmd: vk::CommandBuffer,
    update_timer: GpuTimer,
    /// GPU ms per pass of the last `update_scene` (plus the host's
    /// top-level work), for benchmarks.
    pub update_timings: Vec<(&'static str, f64)>,
    /// Skinned structures refit / rebuilt by the last `update_scene`.
    pub update_counts: [usize; 2],
    /// An update recorded into a frame by `record_scene_update`, awaiting
    /// `finish_scene_update`.
    pending_update: Option<UpdatePlan>,
    readback_ldr: Buffer,
    readback_hdr: Buffer,
    frame_index: u32,
}

fn lighting_inputs(t: &Targets) -> Vec<Input> {
    let mut v: Vec<Input> = t.gbuffer.iter().map(|i| Input::Sampled(i.view)).collect();
    v.push(Input::Sampled(t.depth.view));
    v.push(Input::Storage(t.hdr.view));
    v
}

fn tonemap_inputs(t: &Targets) -> Vec<Input> {
    vec![Input::Storage(t.hdr.view), Input::Storage(t.ldr.view)]
}

fn readback_buffers(ctx: &Context, extent: vk::Extent2D) -> Result<(Buffer, Buffer)> {
    let px = extent.width as u64 * extent.height as u64;
    let ldr = Buffer::new(
        ctx,
        "readback ldr",
        px * 4,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?;
    let hdr = Buffer::new(
        ctx,
        "readback hdr",
        px * 16,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?;
    Ok((ldr, hdr))
}

impl Renderer {
    pub fn new(ctx: &Context, scene: &Scene, extent: vk::Extent2D) -> Result<Renderer> {
        let gpu = GpuScene::upload(ctx, scene)?;
        let targets = Targets::new(ctx, extent)?;
        let gbuffer = GBufferPass::new(ctx, gpu.set.layout)?;
        let no_spec = Specialization::new(&[]);
        let tonemap = ComputePass::new(
            ctx,
            "tonemap",
            "tonemap.comp",
            gpu.set.layout,
            &tonemap_inputs(&targets),
            &[],
            &no_spec,
        )?;
        let timer = GpuTimer::new(ctx, 16)?;
        let cmd = ctx.allocate_command_buffer("frame")?;
        let (readback_ldr, readback_hdr) = readback_buffers(ctx, extent)?;
        let skinning = Skinning::new(ctx, scene, &gpu)?;
        Ok(Renderer {
            skinning,
            rebuild_policy: RebuildPolicy::default(),
            update_cmd: ctx.allocate_command_buffer("scene update")?,
            update_timer: GpuTimer::new(ctx, 8)?,
            update_timings: Vec::new(),
            update_counts: [0; 2],
            pending_update: None,
            gpu,
            targets,
            gbuffer,
            shading: None,
            tonemap,
            needs: SceneNeeds::of(scene),
            accel: None,
            bvh: None,
            timer,
            cmd,
            readback_ldr,
            readback_hdr,
            frame_index: 0,
        })
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.targets.extent
    }

    /// Recreates the per-resolution targets (the caller has waited for idle).
    pub fn resize(&mut self, ctx: &Context, extent: vk::Extent2D) -> Result<()> {
        self.targets.destroy(ctx);
        self.readback_ldr.destroy(ctx);
        self.readback_hdr.destroy(ctx);
        self.targets = Targets::new(ctx, extent)?;
        (self.readback_ldr, self.readback_hdr) = readback_buffers(ctx, extent)?;
        if let Some((_, pass)) = &self.shading {
            pass.bind(ctx, &lighting_inputs(&self.targets));
        }
        self.tonemap.bind(ctx, &tonemap_inputs(&self.targets));
        Ok(())
    }

    /// Brings the GPU copies of everything that can move up to date with
    /// `scene` (already posed by `Scene::animate`): instance transforms and
    /// lights, then in one submission skinning -> skinned BLAS refit (or
    /// rebuild, per `rebuild_policy`) -> TLAS build, or for the compute
    /// backend skinning -> BVH refit -> GPU fit of the top level (whose
    /// topology the host built first). Static per-mesh structures are
    /// untouched. Call only when something moved (so a still scene rebuilds
    /// nothing), with the GPU idle; it waits for its own work. Pass times land in `update_timings`.
    /// The viewer uses `record_scene_update` instead, which needs no wait.
    pub fn update_scene(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let plan = self.plan_update(ctx, scene)?;
        let cmd = self.update_cmd;
        ctx.begin_commands(cmd)?;
        self.record_update(ctx, cmd, scene, &plan)?;
        unsafe { ctx.device.end_command_buffer(cmd)? };
        ctx.submit_and_wait(cmd)?;
        self.finish_update(ctx, plan)
    }

    /// `update_scene` without its own submission, for every backend:
    /// records skinning -> BLAS refit -> TLAS build (compute BVH: refit ->
    /// top-level fit) at the start of `cmd` (before `record`), so a frame is
    /// one submission and the host never waits for the update. Needs a GPU
    /// done with the previous frame, and `finish_scene_update` once `cmd`
    /// has completed.
    pub fn record_scene_update(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        scene: &Scene,
    ) -> Result<()> {
        let plan = self.plan_update(ctx, scene)?;
        self.record_update(ctx, cmd, scene, &plan)?;
        if self.pending_update.replace(plan).is_some() {
            log::debug!("a recorded scene update was never finished; its statistics are lost");
        }
        Ok(())
    }

    /// The host side of a recorded update, once its command buffer is done:
    /// pass times, refit / rebuild counts and the rebuild policy's view of
    /// the deformed bounds. Does nothing when no update is pending.
    pub fn finish_scene_update(&mut self, ctx: &Context) -> Result<()> {
        match self.pending_update.take() {
            Some(plan) => self.finish_update(ctx, plan),
            None => Ok(()),
        }
    }

    /// Host work before an update is recorded: moved transforms and lights,
    /// joint matrices, and which skinned structures refit or rebuild.
    fn plan_update(&mut self, ctx: &Context, scene: &Scene) -> Result<UpdatePlan> {
        self.gpu.update_dynamic(scene)?;
        // Keep only the structures the current backend traces: refitting the
        // other kind every frame would be wasted work (it is rebuilt if the
        // backend changes back).
        match self.shading_config().and_then(|c| c.backend) {
            Some(Backend::Compute) => {
                if let Some((mut a, mut set)) = self.accel.take() {
                    set.destroy(ctx);
                    a.destroy(ctx);
                }
            }
            Some(Backend::Query | Backend::Pipeline) => {
                if let Some(mut b) = self.bvh.take() {
                    b.destroy(ctx);
                }
            }
            _ => {}
        }
        if let Some(s) = &mut self.skinning {
            s.write(scene)?;
        }
        let policy = self.rebuild_policy;
        let bvh = match &mut self.bvh {
            Some(b) => b.prepare_update(scene, &policy)?,
            None => Vec::new(),
        };
        let blas = match self.accel.as_ref().and_then(|(a, _)| a.dynamic.as_ref()) {
            Some(d) => d.blases.iter().map(|b| b.state.next(&policy)).collect(),
            None => Vec::new(),
        };
        Ok(UpdatePlan { blas, bvh })
    }

    /// The update's GPU work, timed by `update_timer`.
    fn record_update(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        scene: &Scene,
        plan: &UpdatePlan,
    ) -> Result<()> {
        let timer = &mut self.update_timer;
        timer.begin_frame(ctx, cmd);
        // Uploads (rebuilt trees) and the previous frame's reads come first.
        let all = vk::PipelineStageFlags2::ALL_COMMANDS;
        crate::vk::memory_barrier(
            ctx,
            cmd,
            (all, vk::AccessFlags2::MEMORY_WRITE | vk::AccessFlags2::MEMORY_READ),
            (all, vk::AccessFlags2::MEMORY_WRITE | vk::AccessFlags2::MEMORY_READ),
        );
        if let Some(s) = &self.skinning {
            pass(ctx, timer, cmd, "skinning", |cmd| {
                s.record(ctx, cmd);
                Ok(())
            })?;
        }
        if let Some((accel, set)) = &mut self.accel {
            if !plan.blas.is_empty() {
                let name = if plan.blas.contains(&Update::Rebuild) { "blas rebuild" } else { "blas refit" };
                pass(ctx, timer, cmd, name, |cmd| {
                    accel.record_dynamic(ctx, cmd, &self.gpu, &plan.blas);
                    Ok(())
                })?;
            }
            pass(ctx, timer, cmd, "tlas build", |cmd| accel.record_tlas(ctx, cmd, scene))?;
            // A TLAS that had to grow is a new object; nothing recorded so
            // far binds the set, so rewriting it here is allowed.
            set.write_acceleration_structure(ctx, 0, accel.tlas.raw);
        }
        if let Some(bvh) = &self.bvh {
            if bvh.skinned_count() > 0 {
                pass(ctx, timer, cmd, "bvh refit", |cmd| {
                    bvh.record_refit(ctx, cmd);
                    Ok(())
                })?;
                pass(ctx, timer, cmd, "top level fit", |cmd| {
                    bvh.record_top_level(ctx, cmd);
                    Ok(())
                })?;
            }
        }
        Ok(())
    }

    /// Host work after the update's commands completed.
    fn finish_update(&mut self, ctx: &Context, plan: UpdatePlan) -> Result<()> {
        let policy = self.rebuild_policy;
        self.update_timings = self.update_timer.results(ctx)?;
        // Judge this frame's results for the next frame's rebuild decisions.
        if let Some((accel, _)) = &mut self.accel {
            if let (Some(d), Some(s)) = (&mut accel.dynamic, &self.skinning) {
                for ((b, bounds), u) in d.blases.iter_mut().zip(s.bounds()?).zip(&plan.blas) {
                    b.state.done(*u, &bounds, &policy);
                }
            }
        }
        if let Some(bvh) = &mut self.bvh {
            bvh.finish_update(&plan.bvh, &policy)?;
            if plan.bvh.contains(&Update::Rebuild) {
                self.update_timings.push(("bvh rebuild (CPU)", bvh.rebuild_ms));
            }
            self.update_timings.push(("top level (CPU)", bvh.top_level_ms));
        }
        let count = |u: &[Update], k: Update| u.iter().filter(|x| **x == k).count();
        self.update_counts = [
            count(&plan.blas, Update::Refit) + count(&plan.bvh, Update::Refit),
            count(&plan.blas, Update::Rebuild) + count(&plan.bvh, Update::Rebuild),
        ];
        Ok(())
    }

    /// Builds the acceleration structure `backend` traces, if missing.
    fn build_structures(&mut self, ctx: &Context, scene: &Scene, backend: Option<Backend>) -> Result<()> {
        match backend {
            Some(Backend::Compute) if self.bvh.is_none() => {
                self.bvh = Some(ComputeBvh::build(ctx, scene, &self.gpu)?);
            }
            Some(Backend::Query | Backend::Pipeline) if self.accel.is_none() => {
                let accel = SceneAccel::build(ctx, scene, &self.gpu)?;
                let set = DescriptorSet::new(
                    ctx,
                    "trace set (TLAS)",
                    &[Binding::one(ash::vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)],
                )?;
                set.write_acceleration_structure(ctx, 0, accel.tlas.raw);
                self.accel = Some((accel, set));
            }
            _ => {}
        }
        Ok(())
    }

    /// The baseline dynamic structures are measured against: skin, then
    /// throw every acceleration structure away and build all of them again
    /// (static BLASes included), as a renderer without refit and
    /// instance-only updates would. `update_timings` gets "skinning" and the
    /// rebuild's wall time.
    pub fn rebuild_all_structures(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        self.update_scene(ctx, scene)?;
        let skinning: Vec<_> =
            self.update_timings.iter().filter(|(n, _)| *n == "skinning").copied().collect();
        let t0 = std::time::Instant::now();
        if let Some((mut a, mut set)) = self.accel.take() {
            set.destroy(ctx);
            a.destroy(ctx);
        }
        if let Some(mut b) = self.bvh.take() {
            b.destroy(ctx);
        }
        self.build_structures(ctx, scene, self.shading_config().and_then(|c| c.backend))?;
        self.update_timings = skinning;
        self.update_timings.push(("full AS rebuild (wall)", t0.elapsed().as_secs_f64() * 1e3));
        Ok(())
    }

    /// The shading variant in use (after `prepare`).
    pub fn shading_config(&self) -> Option<ShadingConfig> {
        self.shading.as_ref().map(|(c, _)| *c)
    }

    /// The descriptor set (set 2) of the traversal `config` uses, if any.
    fn trace_set(&self, config: &ShadingConfig) -> Option<&DescriptorSet> {
        match config.backend {
            Some(Backend::Compute) => self.bvh.as_ref().map(|b| &b.set),
            Some(_) => self.accel.as_ref().map(|(_, s)| s),
            None => None,
        }
    }

    /// Makes the shading pass match `settings` (rebuilding it, and building
    /// the acceleration structures on first need). Waits for the GPU when it
    /// has to rebuild.
    fn ensure_shading(&mut self, ctx: &Context, scene: &Scene, settings: &RenderSettings) -> Result<()> {
        let config =
            ShadingConfig::resolve(ctx, self.needs, settings.mode, settings.effects, settings.backend)?;
        if self.shading.as_ref().is_some_and(|(c, _)| *c == config) {
            return Ok(());
        }
        unsafe { ctx.device.device_wait_idle()? };
        if let Some((_, mut old)) = self.shading.take() {
            old.destroy(ctx);
        }
        self.build_structures(ctx, scene, config.backend)?;
        let extra: Vec<_> = self.trace_set(&config).map(|s| s.layout).into_iter().collect();
        let name = match (config.backend, config.mode) {
            (None, _) => "lighting",
            (Some(_), Mode::Rt) => "rt",
            (Some(_), Mode::Hybrid) => "shade+trace",
        };
        let spec = Specialization::new(&config.specialization());
        let pass = ComputePass::new(
            ctx,
            name,
            config.shader(),
            self.gpu.set.layout,
            &lighting_inputs(&self.targets),
            &extra,
            &spec,
        )?;
        log::info!("shading: {} ({})", config.describe(), config.backend_reason(ctx, settings.backend));
        self.shading = Some((config, pass));
        Ok(())
    }

    /// Fills the frame uniforms for `camera` and selects the shading variant.
    pub fn prepare(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<()> {
        self.ensure_shading(ctx, scene, settings)?;
        let e = self.targets.extent;
        let aspect = e.width as f32 / e.height.max(1) as f32;
        let view = camera.view();
        let proj = camera.projection(aspect);
        let view_proj = proj * view;
        let env = &scene.environment;
        let frame = GpuFrame {
            view: view.to_cols_array(),
            proj: proj.to_cols_array(),
            view_proj: view_proj.to_cols_array(),
            inv_view_proj: view_proj.inverse().to_cols_array(),
            camera_pos: camera.position().to_array(),
            light_count: self.gpu.light_count,
            env_color: env.color.to_array(),
            env_intensity: env.intensity,
            env_ambient: self.gpu.env_mean.to_array(),
            env_rotation: env.rotation,
            resolution: [e.width, e.height],
            has_env_map: env.map.is_some() as u32,
            debug_view: settings.debug_view.code(),
            exposure: settings.exposure,
            frame_index: self.frame_index,
            flags: 0,
            znear: camera.znear,
        };
        debug_assert!(Mat4::from_cols_array(&frame.view).is_finite());
        self.gpu.write_frame(&frame)
    }

    /// Records every pass of one frame; the tone-mapped result is left in
    /// `targets.ldr` in GENERAL layout for the caller (readback or present).
    pub fn record(&mut self, ctx: &Context, cmd: vk::CommandBuffer) -> Result<()> {
        self.timer.begin_frame(ctx, cmd);
        let (gpu, t) = (&self.gpu, &self.targets);
        let (config, shading) = self.shading.as_ref().context("prepare() must run before record()")?;
        if config.mode == Mode::Hybrid {
            pass(ctx, &mut self.timer, cmd, "gbuffer", |cmd| {
                self.gbuffer.record(ctx, cmd, gpu, t);
                Ok(())
            })?;
        }
        let trace_sets: Vec<_> = self.trace_set(config).map(|s| s.set).into_iter().collect();
        pass(ctx, &mut self.timer, cmd, shading.name, |cmd| {
            image_barrier(
                ctx,
                cmd,
                t.hdr.raw,
                t.hdr.aspect,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::GENERAL,
                (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ),
                (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
            );
            shading.dispatch(ctx, cmd, gpu.set.set, &trace_sets, t.extent);
            Ok(())
        })?;
        pass(ctx, &mut self.timer, cmd, "tonemap", |cmd| {
            let compute_write =
                (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE);
            let compute_read =
                (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_READ);
            image_barrier(
                ctx,
                cmd,
                t.hdr.raw,
                t.hdr.aspect,
                vk::ImageLayout::GENERAL,
                vk::ImageLayout::GENERAL,
                compute_write,
                compute_read,
            );
            image_barrier(
                ctx,
                cmd,
                t.ldr.raw,
                t.ldr.aspect,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::GENERAL,
                (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ),
                compute_write,
            );
            self.tonemap.dispatch(ctx, cmd, gpu.set.set, &[], t.extent);
            Ok(())
        })?;
        self.frame_index = self.frame_index.wrapping_add(1);
        Ok(())
    }

    /// Renders one frame offscreen and reads back both outputs.
    pub fn render(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<FrameOutput> {
        self.prepare(ctx, scene, camera, settings)?;
        self.gpu.ray_counters.write(0, &[0u8; 16])?;
        let cmd = self.cmd;
        ctx.begin_commands(cmd)?;
        self.record(ctx, cmd)?;
        let t = &self.targets;
        pass(ctx, &mut self.timer, cmd, "readback", |cmd| {
            let from = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE);
            let to = (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ);
            for (img, buf) in [(&t.ldr, &self.readback_ldr), (&t.hdr, &self.readback_hdr)] {
                image_barrier(
                    ctx,
                    cmd,
                    img.raw,
                    img.aspect,
                    vk::ImageLayout::GENERAL,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    from,
                    to,
                );
                let region = [vk::BufferImageCopy::default()
                    .image_subresource(
                        vk::ImageSubresourceLayers::default().aspect_mask(img.aspect).layer_count(1),
                    )
                    .image_extent(vk::Extent3D { width: t.extent.width, height: t.extent.height, depth: 1 })];
                unsafe {
                    ctx.device.cmd_copy_image_to_buffer(
                        cmd,
                        img.raw,
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        buf.raw,
                        &region,
                    )
                };
            }
            crate::vk::memory_barrier(
                ctx,
                cmd,
                (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
                (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
            );
            Ok(())
        })?;
        unsafe { ctx.device.end_command_buffer(cmd)? };
        ctx.submit_and_wait(cmd)?;
        let timings = self.timer.results(ctx)?;
        let ldr = self.readback_ldr.read()?.to_vec();
        let hdr = bytemuck::pod_collect_to_vec::<u8, f32>(self.readback_hdr.read()?);
        let counts: Vec<u32> = bytemuck::pod_collect_to_vec(self.gpu.ray_counters.read()?);
        let ray_counts = [counts[0], counts[1], counts[2]];
        Ok(FrameOutput { width: t.extent.width, height: t.extent.height, ldr, hdr, timings, ray_counts })
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            let _ = ctx.device.device_wait_idle();
            ctx.device.free_command_buffers(ctx.command_pool, &[self.cmd, self.update_cmd]);
        }
        self.update_timer.destroy(ctx);
        if let Some(mut s) = self.skinning.take() {
            s.destroy(ctx);
        }
        self.readback_ldr.destroy(ctx);
        self.readback_hdr.destroy(ctx);
        self.timer.destroy(ctx);
        self.tonemap.destroy(ctx);
        if let Some((_, mut p)) = self.shading.take() {
            p.destroy(ctx);
        }
        if let Some(mut b) = self.bvh.take() {
            b.destroy(ctx);
        }
        if let Some((mut a, mut set)) = self.accel.take() {
            set.destroy(ctx);
            a.destroy(ctx);
        }
        self.gbuffer.destroy(ctx);
        self.targets.destroy(ctx);
        self.gpu.destroy(ctx);
    }
}
