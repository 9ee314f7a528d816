//! The per-frame decisions made before a frame is recorded: the budget's
//! selection, whether the shadow maps render, the G-buffer's draw list,
//! the ambient term's SH / PRT state, the reference's accumulation and
//! auto visibility's technique. They end in the frame uniforms.

use anyhow::Result;
use ash::vk;

use super::budget::{self, BudgetState};
use super::frame_slots::Finished;
use super::passes::FrameState;
use super::prt_state::PrtState;
use super::shading::{Mode, ShadingConfig};
use super::{cull, reference, uniforms, visibility, AmbientMode, RenderSettings};
use crate::gpu::shared::{FRAME_BUDGET, FRAME_FALLBACK_RASTER, FRAME_SHADOW_MAPS};
use crate::gpu::GpuScene;
use crate::scene::{Camera, Scene};
use crate::vk::frame_ring::Uploads;
use crate::vk::Context;

#[derive(Default)]
pub struct FrameChoices {
    /// The per-object ray-tracing budget's selection across frames.
    budget: BudgetState,
    /// The selection the prepared frame traces (to its download).
    pub(super) budget_traced: Option<Vec<u32>>,
    /// Why this frame leaves out the `shadow_map` pass it has (None: it
    /// records), from the budget's selection.
    shadow_map_left_out: Option<&'static str>,
    /// The G-buffer draws of the prepared frame (frustum-culled).
    pub(super) draw_list: cull::DrawList,
    /// Diffuse PRT transfer on the GPU (prt ambient modes only).
    prt: PrtState,
    /// The `reference` pass's frames accumulated (--reference-samples).
    pub(super) reference: reference::Accumulation,
    frame_index: u32,
    /// The last prepared frame's view-projection and camera position (relative to the render origin): what
    /// glossy reflections' history reprojects through.
    prev_camera: Option<(glam::Mat4, glam::Vec3)>,
    /// Seconds since the previous frame for eye adaptation; None: converge
    /// at once (a still frame: no adaptation history).
    pub adapt_dt: Option<f32>,
    /// `--primary-visibility auto`'s per-view choice (the viewer and bench
    /// switch its measuring on and the viewer feeds it each frame's times).
    pub visibility: visibility::Chooser,
}

impl FrameChoices {
    /// What decides, per frame, which of the created passes record.
    pub(super) fn frame_state(&self) -> FrameState {
        FrameState { shadow_maps_left_out: self.shadow_map_left_out, visibility: self.visibility.technique() }
    }

    /// Makes this frame's choices for `camera` and stages its uniforms.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn prepare(
        &mut self,
        ctx: &Context,
        up: &mut Uploads,
        gpu: &mut GpuScene,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
        config: ShadingConfig,
        extent: vk::Extent2D,
        glossy_history: bool,
    ) -> Result<()> {
        if let (true, Some(b)) = (config.budget, &settings.budget) {
            self.budget_traced =
                Some(self.budget.before_frame(up, gpu, b, scene.objects.len(), config.shadow_fallback)?);
        }
        self.choose_shadow_maps(up, gpu, scene, config)?;
        // The camera relative to the render origin, like every GPU transform.
        let camera = &Camera { world: gpu.origin.relative(&camera.world), ..camera.clone() };
        let view = camera.view().as_mat4();
        let proj = camera.projection(extent.width as f32 / extent.height.max(1) as f32);
        // Only the raster pass draws; pure RT mode and traced visibility find hits by tracing.
        self.draw_list = if self.visibility.before_frame(camera, &scene.bounds, Some(config)) {
            cull::draw_list(scene, gpu, gpu.origin, &(proj.as_dmat4() * camera.view()))
        } else {
            cull::DrawList::default()
        };
        // The path tracer integrates the environment itself: no SH or PRT work.
        let ambient = if settings.mode == Mode::Path {
            AmbientMode::Constant
        } else {
            AmbientMode::resolve(settings, &scene.environment)
        };
        let (exposure, tone) = settings.exposure_for(scene.environment.exposure);
        let settings = &RenderSettings { ambient, exposure, tone, ..*settings };
        self.prt.ensure(ctx, gpu, scene, settings)?;
        let env = &scene.environment;
        // No map: no SH (the constant colour's irradiance is pi L, exactly
        // the constant ambient).
        let sh_radiance = self.prt.sh_radiance(gpu, scene, settings.prt.projection)?;
        let sh = match (settings.ambient, &sh_radiance) {
            (AmbientMode::Constant, _) => None,
            // PRT shades static primary hits; the rest keep SH irradiance.
            // The traced visibility's irradiance is the plain truncation: the accurate one (env_sh.rs).
            (ambient, Some(sh)) => {
                Some(crate::gpu::env_sh::irradiance_uniform(sh, env, ambient == AmbientMode::Traced))
            }
            _ => None,
        };
        let budget_flags = match settings.budget.map(|b| b.fallback) {
            _ if !config.budget => 0,
            Some(budget::Fallback::Raster) => FRAME_BUDGET | FRAME_FALLBACK_RASTER,
            _ => FRAME_BUDGET,
        } | if config.shadow_fallback && self.shadow_map_left_out.is_none() {
            FRAME_SHADOW_MAPS
        } else {
            0
        };
        let inputs = uniforms::Inputs {
            camera,
            view,
            proj,
            extent,
            gpu,
            env,
            frame_index: self.frame_index,
            prev_camera: self.prev_camera.filter(|_| glossy_history),
            adapt_dt: self.adapt_dt,
            budget_flags,
            sh,
            prt: self.prt.radiance().map(|l| crate::gpu::prt_buffer::radiance_uniform(l, env)),
        };
        let frame = uniforms::frame(&inputs, settings, &mut self.reference);
        self.prev_camera = Some((proj * view, camera.position()));
        gpu.write_frame(up, &frame)
    }

    /// The shadow maps render only when some visible object's shadows are
    /// left out (a per-frame choice: the pass itself exists per config).
    fn choose_shadow_maps(
        &mut self,
        up: &mut Uploads,
        gpu: &GpuScene,
        scene: &Scene,
        config: ShadingConfig,
    ) -> Result<()> {
        let left_out = match config.shadow_fallback {
            false => None,
            true if !self.budget.shadow_maps_render() => Some(
                "every visible object's shadows are ray-traced, or the budget left shadows out rather than pay \
                 for maps that cost more than the rays they replace or do not fit",
            ),
            true => {
                gpu.shadow.write_views(up, scene, gpu.origin)?;
                None
            }
        };
        if left_out != self.shadow_map_left_out {
            match left_out {
                Some(why) => log::debug!("frame: left out shadow_map: {why}"),
                None if config.shadow_fallback => log::debug!("frame: shadow_map records"),
                None => {}
            }
            self.shadow_map_left_out = left_out;
        }
        Ok(())
    }

    /// A frame was recorded with these choices.
    pub(super) fn recorded(&mut self) {
        self.frame_index = self.frame_index.wrapping_add(1);
    }

    /// After a completed frame (`done`): the budget's selection for the
    /// next one (nothing without a budget, or when the frame measured
    /// nothing). With frames in flight the statistics are one frame older
    /// than the frame the selection applies to. A frame that traced no rays
    /// although its selection said so (`traced_rays` false: a debug view)
    /// selects from its coverage but teaches the cost model nothing: its
    /// rays and times are not those of the lit frame.
    pub(super) fn finish_budget(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        settings: &RenderSettings,
        done: &Finished,
        screen: budget::Screen,
        traced_rays: bool,
    ) -> Result<()> {
        let Some(b) = &settings.budget else { return Ok(()) };
        let Some((words, traced)) = &done.budget else { return Ok(()) };
        let (traced, timings) = match traced_rays {
            true => (&traced[..], (!done.cold).then_some(&done.timings[..])),
            false => (&[][..], None),
        };
        self.budget.after_frame(words, traced, scene, camera, screen, b, timings)
    }

    /// Makes the next frame under `budget` trace the effects `bits` instead
    /// of what the heuristic chose.
    pub(super) fn set_budget_selection(&mut self, budget: &budget::BudgetSettings, bits: Vec<u32>) {
        self.budget.set_selection(budget, bits);
    }

    /// The budget has what it needs to select under `b` (else `render`
    /// runs frames that only measure first).
    pub(super) fn budget_ready(&self, b: &budget::BudgetSettings) -> bool {
        self.budget.ready(b)
    }

    /// Where the PRT transfer on the GPU came from (None: none there).
    pub(super) fn prt_outcome(&self) -> Option<crate::prt::CacheOutcome> {
        self.prt.outcome()
    }

    /// The budget's last selection and what it was made from.
    pub(super) fn budget_report(&self) -> Option<&budget::BudgetReport> {
        self.budget.last()
    }
}
