//! The renderer: owns the GPU scene, the tracer, the frame's passes and
//! their targets, and records frames. The frame itself is the pass list in
//! `passes::FRAME`, recorded through the pass layer (`frame.rs`), which
//! derives barriers, labels and timestamps from what each pass declares.

pub mod budget;
pub mod choices;
pub mod cull;
pub mod frame;
mod frame_passes;
mod frame_slots;

pub mod kernel;
pub mod occlusion;
pub mod output;
pub mod passes;
pub mod path;
mod prt_state;
pub mod rays;
pub mod readback;
pub mod reference;
pub mod scene_update;
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

use crate::gpu::GpuScene;
use crate::scene::{Camera, Scene};
use crate::vk::{built, Context};
use choices::FrameChoices;
use frame::Recorder;
use frame_passes::FramePasses;
use frame_slots::{FrameReads, FrameSlots};
use passes::{antialias::final_ldr, composite::HDR, Recording};
use scene_update::SceneUpdate;
use shading::{Backend, SceneNeeds, ShadingConfig};
use targets::Targets;
use tracer::Tracer;

pub use frame_slots::Finished;
pub use output::FrameOutput;
pub use path::PathSettings;
pub use settings::{AmbientMode, DebugView, EnvProjection, PrtOptions, ReferenceSettings, RenderSettings};

/// The renderer: a handful of owners, each with one job.
pub struct Renderer {
    pub gpu: GpuScene,
    /// Built on first use by a configuration that traces rays.
    tracer: Option<Box<dyn Tracer>>,
    /// Skinning and the tracer's refit / rebuild of what moved.
    pub update: SceneUpdate,
    /// Frames in flight: staging, downloads, timer, readback buffers.
    slots: FrameSlots,
    /// The passes built for the current configuration, and their targets.
    frame: FramePasses,
    /// This frame's decisions: budget, shadow maps, draws, ambient, reference.
    pub choices: FrameChoices,
    /// The triangles of every draw, fixed at upload (the visibility model's load, read each frame).
    drawn_triangles: u64,
}

impl Renderer {
    pub fn new(ctx: &Context, scene: &Scene, extent: vk::Extent2D) -> Result<Renderer> {
        ctx.caps.limits.check_extent(extent.width, extent.height)?;
        let gpu = GpuScene::upload(ctx, scene)?;
        // Everything after the upload is created into a renderer that owns it
        // from the start, so a failure part-way destroys what exists.
        let drawn_triangles = gpu.draws.iter().map(|d| d.range.index_count as u64 / 3).sum();
        let empty = Renderer {
            drawn_triangles,
            gpu,
            tracer: None,
            update: SceneUpdate::empty(),
            slots: FrameSlots::empty()?,
            frame: FramePasses::new(extent, SceneNeeds::of(scene)),
            choices: FrameChoices::default(),
        };
        built(ctx, empty, |r| {
            r.update = SceneUpdate::new(ctx, scene, &r.gpu)?;
            r.slots = FrameSlots::new(ctx, extent)?;
            Ok(())
        })
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.frame.extent
    }

    /// The targets of the current frame (after `prepare`).
    pub fn targets(&self) -> &Targets {
        &self.frame.targets
    }

    /// Recreates the per-resolution targets (the caller has waited for idle).
    pub fn resize(&mut self, ctx: &Context, extent: vk::Extent2D) -> Result<()> {
        self.slots.resize(ctx, extent)?;
        self.choices.reference.reset();
        self.frame.resize(ctx, extent)
    }

    /// Brings the GPU copies of everything that can move up to date with
    /// `scene` (already posed by `Scene::animate`) in its own submission,
    /// waiting for it: instance transforms and lights, then skinning and
    /// the tracer's update (skinned BLAS refit or rebuild per
    /// `update.policy`, TLAS; or the compute BVH's refit and top level).
    /// Static per-mesh structures are untouched. Call only when something
    /// moved (so a still scene rebuilds nothing). Pass times land in
    /// `update.timings`. The viewer uses `record_scene_update` instead.
    pub fn update_scene(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        self.begin_frame(0)?;
        let cmd = self.update.cmd;
        ctx.begin_commands(cmd)?;
        self.record_scene_update(ctx, cmd, scene)?;
        self.slots.record_downloads(ctx, cmd, None)?;
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
        self.choices.reference.reset(); // the scene moved
        let up = &mut self.slots.uploads("the scene update")?;
        let plan = self.update.plan(up, scene, &mut self.gpu, self.tracer.as_deref_mut())?;
        // A compiling frame sends its passes out in submissions of their own ahead of `cmd`
        // (`record_with`): the update goes out first in one too, or those passes would run before it.
        let compiling = self.compiling(ctx);
        let target = if compiling { ctx.begin_spare(frame_passes::COMPILING)? } else { cmd };
        self.slots.record_uploads(ctx, target)?;
        self.update.record(ctx, target, scene, &self.gpu, self.tracer.as_deref_mut())?;
        if compiling {
            ctx.submit_spare(target)?;
        }
        self.slots.download_update(&self.update, self.tracer.as_deref(), plan)
    }

    /// The next frame is the first of its passes on a device that compiles each pipeline on first use:
    /// it goes out a pass per submission (`record_with`).
    fn compiling(&self, ctx: &Context) -> bool {
        self.frame.passes_new && ctx.caps.device_type == vk::PhysicalDeviceType::CPU
    }

    /// The baseline dynamic structures are measured against: skin, then
    /// throw every acceleration structure away and build all of them again
    /// (static BLASes included), as a renderer without refit and
    /// instance-only updates would. `update.timings` gets "skinning" and
    /// the rebuild's wall time.
    pub fn rebuild_all_structures(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        self.update_scene(ctx, scene)?;
        let timings = &mut self.update.timings;
        timings.retain(|(n, _)| *n == "skinning");
        let t0 = std::time::Instant::now();
        if let Some(mut old) = self.tracer.take() {
            let backend = old.backend();
            old.destroy(ctx);
            // The passes keep their pipelines: the new tracer's set layout is
            // defined identically.
            self.tracer = Some(tracer::create(ctx, backend, scene, &self.gpu)?);
        }
        self.update.timings.push(("full AS rebuild (wall)", t0.elapsed().as_secs_f64() * 1e3));
        Ok(())
    }

    /// The configuration of the current frame (after `prepare`).
    pub fn shading_config(&self) -> Option<ShadingConfig> {
        self.frame.config
    }

    /// The current frame's final LDR target (after `prepare`): what is
    /// read back and presented.
    pub fn output_ldr(&self) -> Result<&'static targets::TargetDesc> {
        self.frame.config.as_ref().map(final_ldr).context("prepare() must run before the output is known")
    }

    /// The G-buffer draws of the last prepared frame: (recorded, left out
    /// as outside the view frustum). (0, 0) in pure ray-traced mode.
    pub fn raster_draws(&self) -> (usize, u32) {
        let d = &self.choices.draw_list;
        (d.draws.len(), d.culled)
    }

    /// The current tracer's load-time build cost and GPU bytes (None before the first frame that
    /// traces, or in a frame that traces nothing).
    pub fn accel_stats(&self) -> Option<tracer::AccelStats> {
        self.tracer.as_ref().map(|t| t.accel_stats())
    }

    /// The scene's GPU memory by category (`GpuScene::memory`).
    pub fn scene_memory(&self) -> crate::gpu::SceneMemory {
        self.gpu.memory()
    }

    /// Bytes of the current frame's render targets (after `prepare`).
    pub fn target_bytes(&self) -> u64 {
        let e = self.frame.extent;
        let per_pixel: u64 = self.frame.targets.describe().iter().map(|(_, b)| *b as u64).sum();
        per_pixel * e.width as u64 * e.height as u64
    }

    /// The triangles of the draws the last prepared frame records (before
    /// occlusion culling).
    pub fn raster_triangles(&self) -> u64 {
        let draws = &self.choices.draw_list.draws;
        draws.iter().map(|d| self.gpu.draws[d.draw as usize].range.index_count as u64 / 3).sum()
    }

    /// Occlusion culling's counters of the last finished frame that culled
    /// (render/occlusion.rs): clusters drawn in phase 1, drawn in phase 2,
    /// occluded, outside the frustum; triangles drawn. None when culling is off.
    pub fn occlusion_counts(&self) -> Option<[u32; crate::gpu::shared::OCC_COUNTER_SLOTS as usize]> {
        let on =
            self.frame.config.is_some_and(|c| c.occlusion) && !self.gpu.clusters.list.clusters.is_empty();
        on.then(|| self.gpu.clusters.counts().ok()).flatten()
    }

    /// Starts the reference's accumulation over at the next frame.
    pub fn reset_reference(&mut self) {
        self.choices.reference.reset();
    }

    /// Frames the reference has accumulated since it last started over.
    pub fn reference_frames(&self) -> u32 {
        self.choices.reference.frames()
    }

    /// Names of the passes the current frame records, in order.
    pub fn pass_names(&self) -> Vec<&'static str> {
        self.frame.names(&self.choices.frame_state())
    }

    /// Auto's primary visibility for a renderer that does not measure (`visibility::model`): the scene's
    /// draws against the frame's pixels, on this device with the tracer `settings` resolve to.
    fn modelled_visibility(&self, ctx: &Context, settings: &RenderSettings) -> settings::PrimaryVisibility {
        let raster = RenderSettings { primary_visibility: settings::PrimaryVisibility::Raster, ..*settings };
        let backend = ShadingConfig::resolve(ctx, self.frame.needs, &raster).ok().and_then(|c| c.backend);
        let e = self.frame.extent;
        let load = visibility::RasterLoad {
            triangles: self.drawn_triangles,
            draws: self.gpu.draws.len() as u64,
            pixels: e.width as u64 * e.height as u64,
        };
        let software = ctx.caps.device_type == vk::PhysicalDeviceType::CPU;
        let pick = visibility::model(load, software, backend == Some(Backend::Compute));
        if pick == settings::PrimaryVisibility::Traced && self.frame.config.is_none() {
            log::info!(
                "primary visibility: traced (auto, not measured: {} triangles + {} draws x {} = {:.1} per pixel, \
                 at least {} and {} in all on a software device with the compute tracer)",
                load.triangles,
                load.draws,
                visibility::MODEL_TRIANGLES_PER_DRAW,
                load.per_pixel(),
                visibility::MODEL_TRACED_PER_PIXEL,
                visibility::MODEL_MIN_LOAD
            );
        }
        pick
    }

    /// Makes the frame's passes, tracer and targets match `settings`. Waits
    /// for the GPU when it has to rebuild.
    fn ensure_frame(&mut self, ctx: &Context, scene: &Scene, settings: &RenderSettings) -> Result<()> {
        let settings = &visibility::effective(settings, self.choices.visibility.measure, || {
            self.modelled_visibility(ctx, settings)
        });
        let config = ShadingConfig {
            inject: !self.frame.injection.is_empty(),
            ..ShadingConfig::resolve(ctx, self.frame.needs, settings)?
        };
        if self.frame.config == Some(config) {
            return Ok(());
        }
        unsafe { ctx.device.device_wait_idle()? };
        self.frame.clear(ctx);
        self.choices.reference.reset(); // new targets
        if self.tracer.as_ref().map(|t| t.backend()) != config.backend {
            if let Some(mut t) = self.tracer.take() {
                t.destroy(ctx);
            }
            if let Some(b) = config.backend {
                self.tracer = Some(tracer::create(ctx, b, scene, &self.gpu)?);
            }
        }
        if config.occlusion {
            self.gpu.ensure_clusters(ctx, scene)?;
        }
        let left_out = self.frame.build(ctx, config, &self.gpu, self.tracer.as_deref())?;
        self.choices.visibility.passes_rebuilt(&config);
        log::info!("frame: {} ({})", config.describe(), config.backend_reason(ctx, settings.backend));
        log::info!("frame: passes {}", self.pass_names().join(" -> "));
        if !left_out.is_empty() {
            log::info!("frame: left out {}", left_out.join("; "));
        }
        let described = self.frame.targets.describe();
        let bytes: u32 = described.iter().map(|(_, b)| b).sum();
        let list: Vec<String> = described.iter().map(|(n, b)| format!("{n} ({b} B)")).collect();
        log::info!("frame: targets {} = {bytes} bytes/pixel", list.join(", "));
        Ok(())
    }

    /// Builds the frame's passes and makes its choices for `camera`; its
    /// host writes are staged in the open frame's slot (`begin_frame`).
    pub fn prepare(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<()> {
        // Before any rebuild: a frame must be open to stage this one's writes.
        self.slots.open_slot("prepare()")?;
        self.ensure_frame(ctx, scene, settings)?;
        let config = self.frame.config.context("no frame configuration")?;
        let up = &mut self.slots.uploads("prepare()")?;
        frame_slots::reset_counters(up, &self.gpu.ray_counters)?;
        let extent = self.frame.extent;
        // A frame of this configuration and size has written it.
        let history =
            self.frame.targets.get(&passes::glossy_temporal::HISTORY).is_some_and(|t| t.laid_out.get());
        self.choices.prepare(ctx, up, &mut self.gpu, scene, camera, settings, config, extent, history)
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
        let config = self.frame.config.context("prepare() must run before record()")?;
        // A software device compiles each pipeline inside the first frame that uses it: that frame goes
        // out a pass per submission, so the log can say how far the compile is.
        let compiling = self.compiling(ctx);
        let head = if compiling { ctx.begin_spare(frame_passes::COMPILING)? } else { cmd };
        self.slots.record_uploads(ctx, head)?;
        let frame = &self.frame;
        let mut rec = Recorder::new(ctx, head, &mut self.slots.timer, Some(&frame.targets));
        let cx = Recording {
            ctx,
            gpu: &self.gpu,
            targets: &frame.targets,
            tracer: self.tracer.as_deref(),
            draws: &self.choices.draw_list,
            injected: &frame.injection,
        };
        if compiling {
            frame.record_compiling(&mut rec, &cx, &self.choices.frame_state())?;
            ctx.submit_spare(rec.cmd)?;
            rec.cmd = cmd;
        } else {
            frame.record(&mut rec, &cx, &self.choices.frame_state())?;
        }
        tail(&mut rec, &frame.targets)?;
        self.choices.recorded();
        self.frame.recorded_cold = std::mem::take(&mut self.frame.passes_new);
        let reads = FrameReads {
            gpu: &self.gpu,
            exposure: config.luminance,
            budget_traced: self.choices.budget_traced.take(),
            cold: self.frame.recorded_cold,
        };
        self.slots.record_downloads(ctx, cmd, Some(reads))
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
        let measures = self.frame.config.is_none_or(|c| c.budget);
        // A debug view traces no rays: the budget measures and selects on
        // lit frames, and the view shows the selection they would trace.
        let lit = RenderSettings { debug_view: DebugView::None, ..*settings };
        // (Up to two calibration frames, and one per cold pass set.)
        for _ in 0..4 {
            if !(measures && settings.budget.is_some_and(|b| !self.choices.budget_ready(&b))) {
                break;
            }
            self.render_frame(ctx, scene, camera, &lit)?;
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
        let cmd = self.slots.cmd;
        ctx.begin_commands(cmd)?;
        let copies = [(self.output_ldr()?, self.slots.readback_ldr.raw), (&HDR, self.slots.readback_hdr.raw)];
        self.record_with(ctx, cmd, |rec, t| readback::record(ctx, rec, t, &copies))?;
        unsafe { ctx.device.end_command_buffer(cmd)? };
        ctx.submit_and_wait(cmd)?;
        let done = self.finish_frame(0)?;
        let ldr = self.slots.readback_ldr.read()?.to_vec();
        let hdr = bytemuck::pod_collect_to_vec::<u8, f32>(self.slots.readback_hdr.read()?);
        self.finish_budget(scene, camera, settings, &done)?;
        self.choices.visibility.after_frame(&done.timings);
        let e = self.frame.extent;
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
            cold: self.frame.recorded_cold,
        })
    }

    /// Starts building the frame of ring slot `slot` (the viewer's frame
    /// slot; offline paths use 0): its host writes are staged there. Call
    /// after the slot's previous frame finished (`finish_frame`).
    pub fn begin_frame(&mut self, slot: usize) -> Result<()> {
        self.slots.begin(slot)
    }

    /// After slot `slot`'s fence: the scene update's results (into
    /// `update`, and the tracer's rebuild policy) and the frame's reads.
    /// Empty when the slot held no frame.
    pub fn finish_frame(&mut self, slot: usize) -> Result<Finished> {
        self.slots.finish(slot, &mut self.update, self.tracer.as_deref_mut())
    }

    /// Replaces the frame ring by one of `slots` frames in flight (the
    /// viewer's); waits for the device.
    pub fn set_frames_in_flight(&mut self, ctx: &Context, slots: usize) -> Result<()> {
        self.slots.set_frames_in_flight(ctx, slots)
    }

    /// After a completed frame (`done`, from `finish_frame`): the budget's
    /// selection for the next one (nothing without a budget, or when the
    /// frame measured nothing). With frames in flight the statistics are
    /// one frame older than the frame the selection applies to.
    pub fn finish_budget(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
        done: &Finished,
    ) -> Result<()> {
        let Some(config) = self.frame.config.filter(|c| c.budget) else { return Ok(()) };
        let screen = budget::Screen { width: self.frame.extent.width, height: self.frame.extent.height };
        self.choices.finish_budget(scene, camera, settings, done, screen, !config.debug_view)
    }

    /// Makes the next frame under `budget` trace the effects `bits` (EFFECT_*
    /// bits per object) instead of what the heuristic chose.
    pub fn set_budget_selection(&mut self, budget: &budget::BudgetSettings, bits: Vec<u32>) {
        self.choices.set_budget_selection(budget, bits);
    }

    /// The budget's last selection and what it was made from.
    pub fn budget_report(&self) -> Option<&budget::BudgetReport> {
        self.choices.budget_report()
    }

    /// Whether the diffuse PRT transfer the last frame shaded with was
    /// loaded from the disk cache or computed (None: no transfer).
    pub fn prt_outcome(&self) -> Option<crate::prt::CacheOutcome> {
        self.choices.prt_outcome()
    }

    /// Fault injection for tests: from the next frame on, these HDR pixels
    /// are overwritten after `composite` by the pass `inject`, which exists
    /// only while armed (empty: disarmed; the next frame rebuilds its passes).
    pub fn inject_radiance(&mut self, pixels: &[passes::inject::Injected]) -> Result<()> {
        passes::inject::check(pixels)?;
        self.frame.injection = pixels.to_vec();
        Ok(())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            let _ = ctx.device.device_wait_idle();
        }
        self.update.destroy(ctx);
        self.slots.destroy(ctx);
        self.frame.destroy(ctx);
        if let Some(mut t) = self.tracer.take() {
            t.destroy(ctx);
        }
        self.gpu.destroy(ctx);
    }
}

crate::destroy_by_method!(Renderer);
