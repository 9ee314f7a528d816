//! The renderer: owns the GPU scene, the tracer, the frame's passes and
//! their targets, and records frames. The frame itself is the pass list in
//! `passes::FRAME`, recorded through the pass layer (`frame.rs`), which
//! derives barriers, labels and timestamps from what each pass declares.

pub mod budget;
pub mod cull;
pub mod frame;
mod frame_results;

pub mod kernel;
pub mod occlusion;
pub mod output;
pub mod passes;
pub mod path;
mod prt_state;
pub mod rays;
pub mod readback;
pub mod reference;
pub mod settings;
pub mod shading;
pub mod skinning;
pub mod srgb;
pub mod supersample;
pub mod targets;
pub mod tone;
pub mod tracer;
mod uniforms;
pub mod uses;
pub mod visibility;

use anyhow::{Context as _, Result};
use ash::vk;

use crate::accel::dynamic::{RebuildPolicy, Update};
use crate::gpu::shared::{FRAME_BUDGET, FRAME_FALLBACK_RASTER};
use crate::gpu::GpuScene;
use crate::scene::{Camera, Scene};
use crate::vk::frame_ring::{FrameRing, Uploads};
use crate::vk::timer::GpuTimer;
use crate::vk::{Buffer, Context};
use frame::{Access, Recorder, SharedBuffer, Use};
use passes::{
    antialias::final_ldr, composite::HDR, Creation, FrameState, Pass, PassDesc, Recording, Upstream,
};
use shading::{SceneNeeds, ShadingConfig};
use skinning::Skinning;
use targets::Targets;
use tone::ExposureState;
use tracer::Tracer;

pub use frame_results::Finished;
pub use output::FrameOutput;
pub use path::PathSettings;
pub use settings::{AmbientMode, DebugView, EnvProjection, PrtOptions, ReferenceSettings, RenderSettings};

/// A pass of the current frame with what it declared.
struct Recorded {
    desc: &'static PassDesc,
    uses: Vec<Use>,
    pass: Box<dyn Pass>,
}

/// The readback and the viewer's blit copy these out of the frame: its
/// final LDR image (anti-aliased, or tone mapping's) and the radiance.
fn outputs(config: &ShadingConfig) -> [Use; 2] {
    [Use::image(final_ldr(config), Access::TransferRead), Use::image(&HDR, Access::TransferRead)]
}

pub struct Renderer {
    pub gpu: GpuScene,
    targets: Targets,
    extent: vk::Extent2D,
    needs: SceneNeeds,
    /// The configuration the passes were built for.
    config: Option<ShadingConfig>,
    passes: Vec<Recorded>,
    /// Built on first use by a configuration that traces rays.
    tracer: Option<Box<dyn Tracer>>,
    pub timer: GpuTimer,
    cmd: vk::CommandBuffer,
    /// Skinning of skinned instances, if the scene has any.
    skinning: Option<Skinning>,
    /// When skinned acceleration structures are rebuilt instead of refit.
    pub rebuild_policy: RebuildPolicy,
    update_cmd: vk::CommandBuffer,
    update_timer: GpuTimer,
    /// GPU ms per pass of the last finished scene update (plus the host's
    /// share), for benchmarks and the viewer (`finish_frame` sets it).
    pub update_timings: Vec<(&'static str, f64)>,
    /// Skinned structures refit / rebuilt by the last finished scene update.
    pub update_counts: [usize; 2],
    /// Per-slot staging of host writes and downloads (frames in flight):
    /// one slot unless the viewer asks for more (`set_frames_in_flight`).
    ring: FrameRing,
    /// The frame being built: its slot, and whether its uploads were
    /// recorded (`begin_frame` .. `record_downloads`).
    open: Option<(usize, bool)>,
    /// Per slot: what its frame left to read after its fence.
    pending: Vec<frame_results::Pending>,
    /// The budget selection the prepared frame traces (to its download).
    budget_traced: Option<Vec<u32>>,
    readback_ldr: Buffer,
    readback_hdr: Buffer,
    frame_index: u32,
    /// Seconds since the previous frame for eye adaptation; None: converge
    /// at once (a still frame: no adaptation history).
    pub adapt_dt: Option<f32>,
    /// Test fault injection into the HDR frame (`inject_radiance`).
    injection: Vec<passes::inject::Injected>,
    /// The per-object ray-tracing budget's selection across frames.
    budget: budget::BudgetState,
    /// Why this frame leaves out the `shadow_map` pass it has (None: it
    /// records), decided in `prepare` from the budget's selection.
    shadow_map_left_out: Option<&'static str>,
    /// The passes were (re)created since the last recorded frame, and
    /// whether the last recorded frame was their first: lavapipe compiles a
    /// shader on first use, inside the GPU timestamps, so that frame's
    /// times say nothing of the passes' cost (the budget ignores them).
    passes_new: bool,
    recorded_cold: bool,
    /// Diffuse PRT transfer on the GPU (prt ambient modes only).
    prt: prt_state::PrtState,
    /// The G-buffer draws of the prepared frame (frustum-culled).
    draw_list: cull::DrawList,
    /// The `reference` pass's frames accumulated (--reference-samples).
    reference: reference::Accumulation,
    /// `--primary-visibility auto`'s per-view choice (the viewer and bench
    /// switch its measuring on and the viewer feeds it each frame's times).
    pub visibility: visibility::Chooser,
}

impl Renderer {
    pub fn new(ctx: &Context, scene: &Scene, extent: vk::Extent2D) -> Result<Renderer> {
        ctx.caps.limits.check_extent(extent.width, extent.height)?;
        let gpu = GpuScene::upload(ctx, scene)?;
        // Everything after the upload is created into a renderer that owns it
        // from the start, so a failure part-way destroys what exists (an
        // error exit leaks no Vulkan object).
        let mut r = Renderer {
            skinning: None,
            rebuild_policy: RebuildPolicy::default(),
            update_cmd: vk::CommandBuffer::null(),
            update_timer: GpuTimer::empty(),
            update_timings: Vec::new(),
            update_counts: [0; 2],
            ring: FrameRing::new(1, "frame ring")?,
            open: None,
            pending: vec![Default::default()],
            budget_traced: None,
            gpu,
            targets: Targets::empty(extent),
            extent,
            needs: SceneNeeds::of(scene),
            config: None,
            passes: Vec::new(),
            tracer: None,
            timer: GpuTimer::empty(),
            cmd: vk::CommandBuffer::null(),
            readback_ldr: Buffer::null(),
            readback_hdr: Buffer::null(),
            frame_index: 0,
            adapt_dt: None,
            injection: Vec::new(),
            budget: budget::BudgetState::default(),
            shadow_map_left_out: None,
            passes_new: false,
            recorded_cold: false,
            prt: Default::default(),
            draw_list: cull::DrawList::default(),
            reference: reference::Accumulation::default(),
            visibility: visibility::Chooser::default(),
        };
        match r.create_resources(ctx, scene) {
            Ok(()) => Ok(r),
            Err(e) => {
                r.destroy(ctx);
                Err(e)
            }
        }
    }

    fn create_resources(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        (self.readback_ldr, self.readback_hdr) = frame_results::readback_buffers(ctx, self.extent)?;
        self.skinning = Skinning::new(ctx, scene, &self.gpu)?;
        self.update_cmd = ctx.allocate_command_buffer("scene update")?;
        self.update_timer = GpuTimer::new(ctx, 8)?;
        self.targets = Targets::new(ctx, self.extent, &[])?;
        self.timer = GpuTimer::new(ctx, 16)?;
        self.cmd = ctx.allocate_command_buffer("frame")?;
        Ok(())
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    /// The targets of the current frame (after `prepare`).
    pub fn targets(&self) -> &Targets {
        &self.targets
    }

    /// Recreates the per-resolution targets (the caller has waited for idle).
    pub fn resize(&mut self, ctx: &Context, extent: vk::Extent2D) -> Result<()> {
        self.readback_ldr.destroy(ctx);
        self.readback_hdr.destroy(ctx);
        (self.readback_ldr, self.readback_hdr) = frame_results::readback_buffers(ctx, extent)?;
        self.extent = extent;
        self.reference.reset();
        let uses: Vec<Use> = self.passes.iter().flat_map(|p| p.uses.iter().copied()).collect();
        if let Some(config) = self.config {
            self.allocate_targets(ctx, &config, &uses)?;
        }
        for p in &self.passes {
            p.pass.bind(ctx, &self.targets);
        }
        Ok(())
    }

    /// Allocates exactly the targets `uses` (the passes' declarations) and
    /// the outputs of `config` name.
    fn allocate_targets(&mut self, ctx: &Context, config: &ShadingConfig, uses: &[Use]) -> Result<()> {
        self.targets.destroy(ctx);
        let all: Vec<Use> = uses.iter().copied().chain(outputs(config)).collect();
        self.targets = Targets::new(ctx, self.extent, &all)?;
        Ok(())
    }

    /// Brings the GPU copies of everything that can move up to date with
    /// `scene` (already posed by `Scene::animate`) in its own submission,
    /// waiting for it: instance transforms and lights, then skinning and
    /// the tracer's update (skinned BLAS refit or rebuild per
    /// `rebuild_policy`, TLAS; or the compute BVH's refit and top level).
    /// Static per-mesh structures are untouched. Call only when something
    /// moved (so a still scene rebuilds nothing). Pass times land in
    /// `update_timings`. The viewer uses `record_scene_update` instead.
    pub fn update_scene(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        self.begin_frame(0)?;
        let cmd = self.update_cmd;
        ctx.begin_commands(cmd)?;
        self.record_scene_update(ctx, cmd, scene)?;
        self.record_downloads(ctx, cmd, false)?;
        unsafe { ctx.device.end_command_buffer(cmd)? };
        ctx.submit_and_wait(cmd)?;
        self.finish_frame(0).map(|_| ())
    }

    /// `update_scene` inside the open frame (`begin_frame`), for every
    /// backend: stages its host writes in the frame's ring slot and records
    /// the update at the start of `cmd` (before `record`), so a frame is one
    /// submission and the host never waits for the update. Its results come
    /// with `finish_frame` of the slot.
    pub fn record_scene_update(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        scene: &Scene,
    ) -> Result<()> {
        let plan = self.plan_update(scene)?;
        self.record_uploads(ctx, cmd)?;
        self.record_update(ctx, cmd, scene)?;
        self.download_update(plan)
    }

    /// Host work before an update is recorded, staged in the open frame's
    /// slot: moved transforms and lights, joint matrices, and the tracer's
    /// refit / rebuild decisions (returned, for its finish).
    fn plan_update(&mut self, scene: &Scene) -> Result<Vec<Update>> {
        self.reference.reset(); // the scene moved
        let (slot, _) = self.open.context("begin_frame() must run before the scene update")?;
        let up = &mut Uploads { ring: &mut self.ring, slot };
        self.gpu.update_dynamic(up, scene)?;
        if let Some(s) = &self.skinning {
            s.write(up, scene, self.gpu.origin)?;
        }
        match &mut self.tracer {
            Some(t) => t.prepare_update(up, scene, &self.gpu, &self.rebuild_policy),
            None => Ok(Vec::new()),
        }
    }

    /// The update's GPU passes, timed by `update_timer`.
    fn record_update(&mut self, ctx: &Context, cmd: vk::CommandBuffer, scene: &Scene) -> Result<()> {
        let mut rec = Recorder::new(ctx, cmd, &mut self.update_timer, None);
        if let Some(s) = &self.skinning {
            let uses = [Use::buffer(SharedBuffer::Geometry, Access::ShaderWrite)];
            rec.pass("skinning", vk::PipelineStageFlags2::COMPUTE_SHADER, &uses, |cmd| {
                s.record(ctx, cmd);
                Ok(())
            })?;
        }
        if let Some(t) = &mut self.tracer {
            t.record_update(&mut rec, scene, &self.gpu)?;
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
        if let Some(mut old) = self.tracer.take() {
            let backend = old.backend();
            old.destroy(ctx);
            // The passes keep their pipelines: the new tracer's set layout is
            // defined identically.
            self.tracer = Some(tracer::create(ctx, backend, scene, &self.gpu)?);
        }
        self.update_timings = skinning;
        self.update_timings.push(("full AS rebuild (wall)", t0.elapsed().as_secs_f64() * 1e3));
        Ok(())
    }

    /// The configuration of the current frame (after `prepare`).
    pub fn shading_config(&self) -> Option<ShadingConfig> {
        self.config
    }

    /// The current frame's final LDR target (after `prepare`): what is
    /// read back and presented.
    pub fn output_ldr(&self) -> Result<&'static targets::TargetDesc> {
        self.config.as_ref().map(final_ldr).context("prepare() must run before the output is known")
    }

    /// The G-buffer draws of the last prepared frame: (recorded, left out
    /// as outside the view frustum). (0, 0) in pure ray-traced mode.
    pub fn raster_draws(&self) -> (usize, u32) {
        (self.draw_list.draws.len(), self.draw_list.culled)
    }

    /// The triangles of the draws the last prepared frame records (before
    /// occlusion culling).
    pub fn raster_triangles(&self) -> u64 {
        self.draw_list
            .draws
            .iter()
            .map(|d| self.gpu.draws[d.draw as usize].range.index_count as u64 / 3)
            .sum()
    }

    /// Occlusion culling's counters of the last finished frame that culled
    /// (render/occlusion.rs): clusters drawn in phase 1, drawn in phase 2,
    /// occluded, outside the frustum; triangles drawn. None when culling is off.
    pub fn occlusion_counts(&self) -> Option<[u32; crate::gpu::shared::OCC_COUNTER_SLOTS as usize]> {
        let on = self.config.is_some_and(|c| c.occlusion) && !self.gpu.clusters.list.clusters.is_empty();
        on.then(|| self.gpu.clusters.counts().ok()).flatten()
    }

    /// Starts the reference's accumulation over at the next frame.
    pub fn reset_reference(&mut self) {
        self.reference.reset();
    }

    /// Frames the reference has accumulated since it last started over.
    pub fn reference_frames(&self) -> u32 {
        self.reference.frames()
    }

    /// Names of the passes the current frame records, in order.
    pub fn pass_names(&self) -> Vec<&'static str> {
        let state = self.frame_state();
        self.passes.iter().filter(|p| (p.desc.this_frame)(&state).is_none()).map(|p| p.desc.name).collect()
    }

    /// What decides, per frame, which of the created passes record.
    fn frame_state(&self) -> FrameState {
        FrameState { shadow_maps_left_out: self.shadow_map_left_out, visibility: self.visibility.technique() }
    }

    /// Makes the frame's passes, tracer and targets match `settings`. Waits
    /// for the GPU when it has to rebuild.
    fn ensure_frame(&mut self, ctx: &Context, scene: &Scene, settings: &RenderSettings) -> Result<()> {
        let settings = &visibility::effective(settings, self.visibility.measure);
        let config = ShadingConfig {
            inject: !self.injection.is_empty(),
            ..ShadingConfig::resolve(ctx, self.needs, settings)?
        };
        if self.config == Some(config) {
            return Ok(());
        }
        unsafe { ctx.device.device_wait_idle()? };
        for mut p in self.passes.drain(..) {
            p.pass.destroy(ctx);
        }
        self.config = None;
        self.reference.reset(); // new targets
        if self.tracer.as_ref().map(|t| t.backend()) != config.backend {
            if let Some(mut t) = self.tracer.take() {
                t.destroy(ctx);
            }
            if let Some(b) = config.backend {
                self.tracer = Some(tracer::create(ctx, b, scene, &self.gpu)?);
            }
        }
        let mut left_out = Vec::new();
        let mut chosen = Vec::new();
        for desc in passes::frame(&config) {
            match (desc.skip)(&config) {
                Some(why) => left_out.push(format!("{}: {why}", desc.name)),
                None => chosen.push(desc),
            }
        }
        if config.occlusion {
            self.gpu.ensure_clusters(ctx, scene)?;
        }
        // Targets first (passes bind them), from what the passes declare.
        self.passes = Vec::new();
        // Each pass sees what the passes before it write (its inputs' handles).
        let mut upstream = vec![Upstream::default()];
        let mut uses: Vec<Vec<Use>> = Vec::new();
        for d in &chosen {
            let before = upstream.last().expect("one per pass and the start");
            let u = (d.uses)(&config, before);
            let mut after = before.clone();
            after.add(&u);
            upstream.push(after);
            uses.push(u);
        }
        self.allocate_targets(ctx, &config, &uses.iter().flatten().copied().collect::<Vec<_>>())?;
        for ((desc, uses), upstream) in chosen.into_iter().zip(uses).zip(&upstream) {
            let init = Creation {
                ctx,
                config: &config,
                gpu: &self.gpu,
                targets: &self.targets,
                tracer: self.tracer.as_deref(),
                upstream,
            };
            let pass = (desc.create)(&init).with_context(|| format!("creating pass {}", desc.name))?;
            self.passes.push(Recorded { desc, uses, pass });
        }
        self.passes_new = true;
        self.visibility.passes_rebuilt(&config);
        if ctx.caps.device_type == vk::PhysicalDeviceType::CPU {
            log::info!(
                "frame: compiling shaders: a software device compiles each pipeline on first use, inside the \
                 first frame (seconds per variant the first time; Mesa keeps them in its disk cache)"
            );
        }
        log::info!("frame: {} ({})", config.describe(), config.backend_reason(ctx, settings.backend));
        log::info!("frame: passes {}", self.pass_names().join(" -> "));
        if !left_out.is_empty() {
            log::info!("frame: left out {}", left_out.join("; "));
        }
        let described = self.targets.describe();
        let bytes: u32 = described.iter().map(|(_, b)| b).sum();
        let list: Vec<String> = described.iter().map(|(n, b)| format!("{n} ({b} B)")).collect();
        log::info!("frame: targets {} = {bytes} bytes/pixel", list.join(", "));
        self.config = Some(config);
        Ok(())
    }

    /// Fills the frame uniforms for `camera` and builds the frame's passes;
    /// its host writes are staged in the open frame's slot (`begin_frame`).
    pub fn prepare(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<()> {
        let (slot, _) = self.open.context("begin_frame() must run before prepare()")?;
        self.ensure_frame(ctx, scene, settings)?;
        let up = &mut Uploads { ring: &mut self.ring, slot };
        frame_results::reset_counters(up, &self.gpu.ray_counters)?;
        let e = self.extent;
        let aspect = e.width as f32 / e.height.max(1) as f32;
        // The camera relative to the render origin, like every GPU transform.
        let budget_on = self.config.is_some_and(|c| c.budget);
        if let (true, Some(b)) = (budget_on, &settings.budget) {
            self.budget_traced = Some(self.budget.before_frame(up, &self.gpu, b, scene.objects.len())?);
        }
        // The shadow maps render only when some visible object's shadows are
        // left out (a per-frame choice: the pass itself exists per config).
        let left_out = match self.config.is_some_and(|c| c.shadow_fallback) {
            false => None,
            true if !self.budget.shadows_left_out() => Some("every visible object's shadows are ray-traced"),
            true => {
                self.gpu.shadow.write_views(up, scene, self.gpu.origin)?;
                None
            }
        };
        if left_out != self.shadow_map_left_out {
            match left_out {
                Some(why) => log::debug!("frame: left out shadow_map: {why}"),
                None if self.config.is_some_and(|c| c.shadow_fallback) => {
                    log::debug!("frame: shadow_map records")
                }
                None => {}
            }
            self.shadow_map_left_out = left_out;
        }
        let camera = &Camera { world: self.gpu.origin.relative(&camera.world), ..camera.clone() };
        let view = camera.view().as_mat4();
        let proj = camera.projection(aspect);
        // Only the raster pass draws; pure RT mode and traced visibility find hits by tracing.
        self.draw_list = if self.visibility.before_frame(camera, &scene.bounds, self.config) {
            cull::draw_list(scene, &self.gpu, self.gpu.origin, &(proj.as_dmat4() * camera.view()))
        } else {
            cull::DrawList::default()
        };
        let path_mode = settings.mode == shading::Mode::Path;
        // The path tracer integrates the environment itself: no SH or PRT work.
        let ambient = if path_mode {
            AmbientMode::Constant
        } else {
            AmbientMode::resolve(settings, &scene.environment)
        };
        let settings = &RenderSettings { ambient, ..*settings };
        self.prt.ensure(ctx, &mut self.gpu, scene, settings)?;
        let env = &scene.environment;
        // No map: no SH (the constant colour's irradiance is pi L, exactly
        // the constant ambient).
        let sh_radiance = self.prt.sh_radiance(&self.gpu, scene, settings.prt.projection)?;
        let sh = match (settings.ambient, &sh_radiance) {
            (AmbientMode::Constant, _) => None,
            // PRT shades static primary hits; the rest keep SH irradiance.
            (_, Some(sh)) => Some(crate::gpu::env_sh::irradiance_uniform(sh, env)),
            _ => None,
        };
        let budget_flags = match settings.budget.map(|b| b.fallback) {
            _ if !budget_on => 0,
            Some(budget::Fallback::Raster) => FRAME_BUDGET | FRAME_FALLBACK_RASTER,
            _ => FRAME_BUDGET,
        };
        let inputs = uniforms::Inputs {
            camera,
            view,
            proj,
            extent: e,
            gpu: &self.gpu,
            env,
            frame_index: self.frame_index,
            adapt_dt: self.adapt_dt,
            budget_flags,
            sh,
            prt: self.prt.radiance().map(|l| crate::gpu::prt_buffer::radiance_uniform(l, env)),
        };
        let frame = uniforms::frame(&inputs, settings, &mut self.reference);
        self.gpu.write_frame(&mut Uploads { ring: &mut self.ring, slot }, &frame)
    }

    /// Records every pass of one frame; the displayable result is in the
    /// `output_ldr()` target for the caller (readback or present).
    pub fn record(&mut self, ctx: &Context, cmd: vk::CommandBuffer) -> Result<()> {
        self.record_with(ctx, cmd, |_, _| Ok(()))
    }

    /// `record`, then `tail` with the same recorder (so its passes' barriers
    /// follow from the frame's): the readback, the viewer's blit.
    pub fn record_with(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        tail: impl FnOnce(&mut Recorder, &Targets) -> Result<()>,
    ) -> Result<()> {
        anyhow::ensure!(self.config.is_some(), "prepare() must run before record()");
        self.record_uploads(ctx, cmd)?;
        let state = self.frame_state();
        let mut rec = Recorder::new(ctx, cmd, &mut self.timer, Some(&self.targets));
        let cx = Recording {
            ctx,
            gpu: &self.gpu,
            targets: &self.targets,
            tracer: self.tracer.as_deref(),
            draws: &self.draw_list,
            injected: &self.injection,
        };
        for p in &self.passes {
            if (p.desc.this_frame)(&state).is_some() {
                continue;
            }
            rec.pass(p.desc.name, p.pass.stage(), &p.uses, |cmd| {
                p.pass.record(&cx, cmd);
                Ok(())
            })?;
        }
        tail(&mut rec, &self.targets)?;
        self.frame_index = self.frame_index.wrapping_add(1);
        self.recorded_cold = std::mem::take(&mut self.passes_new);
        self.record_downloads(ctx, cmd, true)
    }

    /// Renders one frame offscreen and reads back both outputs. With a
    /// budget and no selection for it yet, frames that only measure run
    /// first (the selection lags the statistics by a frame; effects mode
    /// calibrates its cost model with one frame tracing nothing and one
    /// tracing everything).
    pub fn render(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<FrameOutput> {
        // (A budget the frame leaves out, with nothing traced, needs none.)
        let measures = self.config.is_none_or(|c| c.budget);
        // (Up to two calibration frames, and one per cold pass set.)
        for _ in 0..4 {
            if !(measures && settings.budget.is_some_and(|b| !self.budget.ready(&b))) {
                break;
            }
            self.render_frame(ctx, scene, camera, settings)?;
        }
        self.render_frame(ctx, scene, camera, settings)
    }

    fn render_frame(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<FrameOutput> {
        self.begin_frame(0)?;
        self.prepare(ctx, scene, camera, settings)?;
        let cmd = self.cmd;
        ctx.begin_commands(cmd)?;
        let copies = [(self.output_ldr()?, self.readback_ldr.raw), (&HDR, self.readback_hdr.raw)];
        self.record_with(ctx, cmd, |rec, t| readback::record(ctx, rec, t, &copies))?;
        unsafe { ctx.device.end_command_buffer(cmd)? };
        ctx.submit_and_wait(cmd)?;
        let done = self.finish_frame(0)?;
        let ldr = self.readback_ldr.read()?.to_vec();
        let hdr = bytemuck::pod_collect_to_vec::<u8, f32>(self.readback_hdr.read()?);
        self.finish_budget(scene, camera, settings, &done)?;
        self.visibility.after_frame(&done.timings);
        let e = self.extent;
        Ok(FrameOutput {
            width: e.width,
            height: e.height,
            ldr,
            hdr,
            timings: done.timings,
            ray_counts: done.ray_counts,
            truncated_pixels: done.truncated_pixels,
            bad_pixels: done.bad_pixels,
            exposure: done.exposure,
            cold: self.recorded_cold,
        })
    }

    /// Fault injection for tests: from the next frame on, these HDR pixels
    /// are overwritten after `composite` by the pass `inject`, which exists
    /// only while armed (empty: disarmed; the next frame rebuilds its passes).
    pub fn inject_radiance(&mut self, pixels: &[passes::inject::Injected]) -> Result<()> {
        passes::inject::check(pixels)?;
        self.injection = pixels.to_vec();
        Ok(())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            let _ = ctx.device.device_wait_idle();
            let cmds: Vec<vk::CommandBuffer> =
                [self.cmd, self.update_cmd].into_iter().filter(|c| *c != vk::CommandBuffer::null()).collect();
            if !cmds.is_empty() {
                ctx.device.free_command_buffers(ctx.command_pool, &cmds);
            }
        }
        self.update_timer.destroy(ctx);
        if let Some(mut s) = self.skinning.take() {
            s.destroy(ctx);
        }
        self.readback_ldr.destroy(ctx);
        self.readback_hdr.destroy(ctx);
        self.ring.destroy(ctx);
        self.timer.destroy(ctx);
        for mut p in self.passes.drain(..) {
            p.pass.destroy(ctx);
        }
        if let Some(mut t) = self.tracer.take() {
            t.destroy(ctx);
        }
        self.targets.destroy(ctx);
        self.gpu.destroy(ctx);
    }
}

crate::destroy_by_method!(Renderer);
