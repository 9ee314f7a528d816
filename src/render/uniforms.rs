//! The frame uniform (`GpuFrame`): camera, environment, ambient (SH / PRT), tone mapping, flags and the
//! accumulation's frame count, assembled from what `Renderer::prepare` decided for the frame.

use ash::vk;
use glam::Mat4;

use super::reference::Accumulation;
use super::settings::RenderSettings;
use super::shading::Mode;
use super::tone::{ToneOperator, ToneSettings};
use crate::gpu::shared::{
    FRAME_AMBIENT_PRT, FRAME_AMBIENT_SH, FRAME_AO_BOUNCE_LIGHTS, FRAME_AO_BOUNCE_SKY, FRAME_AO_EMITTERS,
    FRAME_AO_SKY, FRAME_COUNT_RAYS, FRAME_GLOSSY_HISTORY, FRAME_GLOSSY_TEMPORAL, FRAME_OPAQUE_OCCLUDERS,
    SH_IRRADIANCE_COEFFS, SH_PRT_MAX_COEFFS, TERM_EMITTERS, TERM_INDIRECT, TERM_VISIBILITY,
};
use crate::gpu::types::GpuFrame;
use crate::gpu::GpuScene;
use crate::scene::{Camera, Environment};

/// What the uniform is made of besides the settings.
pub struct Inputs<'a> {
    /// The camera relative to the render origin, like every GPU transform.
    pub camera: &'a Camera,
    pub view: Mat4,
    pub proj: Mat4,
    pub extent: vk::Extent2D,
    pub gpu: &'a GpuScene,
    pub env: &'a Environment,
    pub frame_index: u32,
    /// The previous frame's view-projection and camera position where glossy reflections have a history
    /// laid out for this configuration and size (FRAME_GLOSSY_HISTORY).
    pub prev_camera: Option<(Mat4, glam::Vec3)>,
    pub adapt_dt: Option<f32>,
    /// FRAME_BUDGET / FRAME_FALLBACK_RASTER as the budget decided.
    pub budget_flags: u32,
    /// The environment's SH irradiance, when the ambient uses it.
    pub sh: Option<[[f32; 4]; SH_IRRADIANCE_COEFFS as usize]>,
    /// The environment's radiance coefficients, when PRT shades.
    pub prt: Option<[[f32; 4]; SH_PRT_MAX_COEFFS as usize]>,
}

/// The frame uniform; an accumulating frame (path, reference, terms)
/// counts on in `accumulation`, or starts over when what it shows changed.
pub fn frame(i: &Inputs, settings: &RenderSettings, accumulation: &mut Accumulation) -> GpuFrame {
    let mut flags = i.budget_flags;
    if i.sh.is_some() {
        flags |= FRAME_AMBIENT_SH;
    }
    if i.prt.is_some() {
        flags |= FRAME_AMBIENT_PRT;
    }
    let view_proj = i.proj * i.view;
    if settings.glossy_temporal {
        flags |= FRAME_GLOSSY_TEMPORAL;
    }
    if settings.effects.count_rays {
        flags |= FRAME_COUNT_RAYS;
    }
    // The attribution's terms (report/attribution.rs) stand in for the parts of the traced ambient they
    // cover: the environment's light (visibility), the hits' direct light (indirect), their emission.
    let supplied = |term: u32| settings.terms & term != 0;
    if !supplied(TERM_VISIBILITY) {
        flags |= FRAME_AO_SKY;
    }
    if settings.ambient_bounce && !supplied(TERM_INDIRECT) {
        flags |= FRAME_AO_BOUNCE_LIGHTS;
    }
    // Emissive surfaces are direct light: `--no-indirect` keeps them.
    if !supplied(TERM_EMITTERS) {
        flags |= FRAME_AO_EMITTERS;
    }
    if settings.ambient_bounce {
        flags |= FRAME_AO_BOUNCE_SKY;
    }
    let (prev_view_proj, prev_camera_pos) = match i.prev_camera.filter(|_| settings.glossy_temporal) {
        Some((vp, pos)) => {
            flags |= FRAME_GLOSSY_HISTORY;
            (vp, pos)
        }
        None => (view_proj, i.camera.position()),
    };
    let (env, e) = (i.env, i.extent);
    let mut frame = GpuFrame {
        view: i.view.to_cols_array(),
        proj: i.proj.to_cols_array(),
        view_proj: view_proj.to_cols_array(),
        inv_view_proj: view_proj.inverse().to_cols_array(),
        prev_view_proj: prev_view_proj.to_cols_array(),
        prev_camera_pos: prev_camera_pos.to_array(),
        max_depth: settings.effects.max_depth,
        min_weight: settings.effects.min_weight,
        camera_pos: i.camera.position().to_array(),
        light_count: i.gpu.light_count,
        env_color: env.color.to_array(),
        env_intensity: env.intensity,
        env_ambient: i.gpu.env_mean.to_array(),
        env_rotation: env.rotation,
        resolution: [e.width, e.height],
        has_env_map: env.map.is_some() as u32,
        debug_view: settings.debug_view.code(),
        exposure: settings.exposure,
        frame_index: i.frame_index,
        flags,
        znear: i.camera.znear,
        sh_irradiance: i.sh.unwrap_or_default(),
        sh_radiance: i.prt.unwrap_or([[0.0; 4]; SH_PRT_MAX_COEFFS as usize]),
        ..tone(&settings.tone, i.adapt_dt)
    };
    if settings.mode == Mode::Path {
        frame.flags |= FRAME_OPAQUE_OCCLUDERS;
        frame.accum_bounces = settings.path.max_bounces;
        frame.path_clamp = settings.path.clamp.unwrap_or(0.0);
        frame.accum_frame = accumulation.next(&frame);
    } else if let Some(r) = settings.reference {
        frame.accum_bounces = r.bounces;
        frame.accum_frame = accumulation.next(&frame);
    } else if settings.terms != 0 {
        // The `terms` pass: the selection where the others keep their path length.
        frame.accum_bounces = settings.terms;
        frame.accum_frame = accumulation.next(&frame);
    }
    debug_assert!(Mat4::from_cols_array(&frame.view).is_finite());
    frame
}

/// The frame uniforms' tone-mapping fields.
fn tone(t: &ToneSettings, adapt_dt: Option<f32>) -> GpuFrame {
    let white = match (t.operator, t.white) {
        (_, Some(w)) => w,
        // <= 0: the frame's brightest pixel (measured by `luminance`).
        (ToneOperator::ReinhardWhite, None) => 0.0,
        _ => 1.0,
    };
    GpuFrame {
        tonemap: t.operator.code(),
        auto_exposure: t.auto_exposure.code(),
        key: t.key,
        white,
        adapt_dt: adapt_dt.unwrap_or(0.0),
        hist_low: t.histogram_low,
        hist_high: t.histogram_high,
        speed_brighten: t.speed_brighten,
        speed_darken: t.speed_darken,
        ..bytemuck::Zeroable::zeroed()
    }
}
