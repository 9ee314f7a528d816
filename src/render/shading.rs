//! What a frame runs: the render mode, the secondary effects the scene needs (and the user did not
//! switch off), the ray backend and whether a debug view replaces the lighting. The passes decide from
//! this whether they record; unneeded effects are compiled out through specialization constants (the
//! recursion limits and ray counting are frame uniforms instead, so the configuration ignores them), and
//! with none at all no ray is traced and no acceleration structure is built.

use anyhow::{bail, Result};

pub use crate::gpu::shared::{GLOSSY_ROUGHNESS, MIRROR_ROUGHNESS};
use crate::gpu::shared::{SPEC_REFLECTIONS, SPEC_REFRACTIONS, SPEC_SHADOWS};
use crate::scene::{LightKind, Scene};
use crate::vk::limits::Limits;
use crate::vk::{Context, RtEnables};

pub use super::settings::{AaMode, AmbientMode, Backend, Effects, Mode};

/// What the scene contains that each effect needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneNeeds {
    pub shadows: bool,
    /// Mirrors or glossy materials.
    pub reflections: bool,
    /// At most MIRROR_ROUGHNESS rough (or coated that smooth): the `specular` chain reflects them.
    pub mirrors: bool,
    /// Rougher, up to GLOSSY_ROUGHNESS: the `glossy` pass samples their lobe.
    pub glossy: bool,
    pub refractions: bool,
    /// A directional or spot light casts shadows (the budget's raster fallback renders shadow maps for them).
    pub shadow_maps: bool,
    /// Something lights the scene (the environment, a light, an emissive material) and something can
    /// occlude or bounce it: `--ambient traced` has something to trace.
    pub ambient_occluders: bool,
    /// An instance's material emits: the traced ambient samples the emissive triangles.
    pub emitters: bool,
    /// The scene file's `[environment] ambient`.
    pub scene_ambient: Option<AmbientMode>,
    /// The scene file's `[environment] exposure`.
    pub scene_exposure: Option<crate::scene::SceneExposure>,
    /// Triangles of the largest primitive (one BLAS each) and the instance
    /// count (TLAS entries), checked against the driver's limits.
    pub largest_primitive_triangles: u64,
    pub instances: u64,
}

impl SceneNeeds {
    pub fn of(scene: &Scene) -> SceneNeeds {
        let used: Vec<usize> = scene.instances.iter().map(|i| scene.instance_material(i)).collect();
        let any_occluder = scene.instances.iter().any(|i| {
            scene.objects.get(i.object).is_none_or(|o| o.props.casts_shadows)
                && scene.materials[scene.instance_material(i)].casts_shadows
        });
        // A coat's lobe gets mirror and glossy rays as a base's of its roughness.
        let ranges = |m: &usize| {
            let m = &scene.materials[*m];
            std::iter::once(m.roughness_range()).chain(m.coat_roughness_range())
        };
        let mirrors = used.iter().any(|m| ranges(m).any(|r| r.0 <= MIRROR_ROUGHNESS));
        let glossy =
            used.iter().any(|m| ranges(m).any(|r| r.1 > MIRROR_ROUGHNESS && r.0 <= GLOSSY_ROUGHNESS));
        let env = &scene.environment;
        let env_lit = env.intensity > 0.0 && (env.map.is_some() || env.color.max_element() > 0.0);
        let emitters = used.iter().any(|&m| scene.materials[m].emissive.iter().any(|c| *c > 0.0));
        SceneNeeds {
            shadows: any_occluder && scene.lights.iter().any(|l| l.casts_shadows && light_is_on(l)),
            ambient_occluders: any_occluder && (env_lit || scene.lights.iter().any(light_is_on) || emitters),
            emitters,
            scene_ambient: AmbientMode::of_scene(env),
            scene_exposure: env.exposure,
            reflections: mirrors || glossy,
            mirrors,
            glossy,
            refractions: used.iter().any(|&m| {
                let mat = &scene.materials[m];
                mat.transmission > 0.0 && mat.metallic < 1.0
            }),
            shadow_maps: any_occluder
                && scene.lights.iter().any(|l| crate::gpu::shadow_map::mapped(l) && light_is_on(l)),
            largest_primitive_triangles: scene
                .instances
                .iter()
                .map(|i| scene.meshes[i.mesh].primitives[i.primitive].indices.len() as u64 / 3)
                .max()
                .unwrap_or(0),
            instances: scene.instances.len() as u64,
        }
    }
}

/// The backend for `requested` on a device with `rt` enabled. The hardware backends must hold the scene
/// within the driver's acceleration-structure limits (lavapipe before Mesa 25.2.7: 2^24 - 1 triangles per
/// BLAS): `auto` falls back to the compute BVH with a warning, an explicit request fails with the numbers,
/// before a driver call could crash on them. On a `software` device `auto` takes the compute BVH: the
/// driver's traversal runs on the CPU too and measured slower than ours on every shipped scene (lavapipe, 2
/// threads: 2x on Sponza, ~50x / ~100x on the armadillo; bench/results/report/*/report.md, knob backend).
pub fn pick_backend(
    requested: Backend,
    rt: &RtEnables,
    limits: &Limits,
    needs: &SceneNeeds,
    software: bool,
) -> Result<Backend> {
    let too_big = if needs.largest_primitive_triangles > limits.max_primitive_count {
        Some(format!(
            "a mesh primitive has {} triangles, more than this driver's acceleration-structure limit \
             (maxPrimitiveCount {})",
            needs.largest_primitive_triangles, limits.max_primitive_count
        ))
    } else if needs.instances > limits.max_instance_count {
        Some(format!(
            "the scene has {} instances, more than this driver's limit (maxInstanceCount {})",
            needs.instances, limits.max_instance_count
        ))
    } else {
        None
    };
    let hardware = |name: &str, ext: &str, available: bool, backend: Backend| -> Result<Backend> {
        if !available {
            bail!("--backend {name}: the device has no usable {ext} (see `info`)");
        }
        if let Some(why) = &too_big {
            bail!("--backend {name}: {why}; split the mesh or use --backend compute");
        }
        Ok(backend)
    };
    Ok(match requested {
        Backend::Query => hardware("query", "VK_KHR_ray_query", rt.ray_query, Backend::Query)?,
        Backend::Pipeline => {
            hardware("pipeline", "VK_KHR_ray_tracing_pipeline", rt.ray_tracing_pipeline, Backend::Pipeline)?
        }
        Backend::Auto if software => Backend::Compute,
        Backend::Auto if (rt.ray_query || rt.ray_tracing_pipeline) && too_big.is_some() => {
            log::warn!("{}: using the compute BVH backend", too_big.unwrap_or_default());
            Backend::Compute
        }
        Backend::Auto if rt.ray_query => Backend::Query,
        Backend::Auto if rt.ray_tracing_pipeline => Backend::Pipeline,
        Backend::Auto => Backend::Compute,
        b => b,
    })
}

/// A CPU implementation of Vulkan (lavapipe, SwiftShader).
fn software(ctx: &Context) -> bool {
    ctx.caps.device_type == ash::vk::PhysicalDeviceType::CPU
}

fn light_is_on(l: &crate::scene::Light) -> bool {
    let cone_open = match l.kind {
        LightKind::Spot { outer_cone, .. } => outer_cone > 0.0,
        _ => true,
    };
    l.intensity > 0.0 && l.color.max_element() > 0.0 && cone_open
}

/// The resolved configuration of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingConfig {
    pub mode: Mode,
    /// The effects that run: wanted and needed. The per-frame values (`max_depth`, `min_weight`,
    /// `count_rays`: frame uniforms) are at their defaults here, so changing them rebuilds nothing.
    pub effects: Effects,
    /// None: no ray is traced (deferred shading only).
    pub backend: Option<Backend>,
    /// A G-buffer debug view replaces the lighting.
    pub debug_view: bool,
    /// What the scene contains that the effects need.
    pub needs: SceneNeeds,
    /// The frame's luminance is measured (auto exposure, or `reinhard-white`'s white point from the frame's
    /// maximum): the `luminance` pass runs.
    pub luminance: bool,
    /// The per-object ray budget selects which pixels get traced effects: the `heuristic` pass runs and the
    /// ray passes honour it (only when something is traced, or its debug view shows).
    pub budget: bool,
    /// The budget's raster fallback for shadows: the `shadow_map` pass
    /// exists (it records only in frames where a shadow bit is off).
    pub shadow_fallback: bool,
    /// Anti-aliasing after tone mapping (left out in debug views).
    pub aa: AaMode,
    /// RenderSettings::edge_aa_tiled.
    pub edge_aa_tiled: bool,
    /// The ray-traced ambient reference runs (--reference-samples; not in
    /// debug views): the `reference` pass exists and traces.
    pub reference: bool,
    /// The report's attribution terms run (RenderSettings::terms; not in
    /// debug views, not beside `reference`): the `terms` pass exists.
    pub terms: bool,
    /// How hybrid mode finds primary hits: `Raster` (pass `gbuffer`), `Traced` (pass `visibility_trace`) or
    /// `Auto` (both exist, each frame records one: render/visibility.rs); `Raster` in pure ray-traced mode.
    pub visibility: crate::render::settings::PrimaryVisibility,
    /// The raster G-buffer culls occluded clusters (render/occlusion.rs): asked for, the pass rasterizes,
    /// and the device has multi-draw indirect with a first instance.
    pub occlusion: bool,
    /// Fault injection is armed (tests: `Renderer::inject_radiance`): the `inject` pass exists.
    pub inject: bool,
    /// RenderSettings::glossy_temporal: the `glossy temporal` pass and the history exist (the viewer);
    /// without it the filter reads the frame's sample itself.
    pub glossy_temporal: bool,
    /// `--ambient traced` where the environment lights the scene and something occludes it (not in a
    /// debug view, not beside the reference, which replaces the ambient): passes `ao` and `ao filter`.
    pub ambient_visibility: bool,
    /// Beside it, the emitters' light on specular lobes no glossy ray samples: the scene emits, so `ao`,
    /// `ao filter` and `composite` take their variants with the `emitter specular` targets.
    pub ao_emitter_specular: bool,
}

impl ShadingConfig {
    pub fn resolve(
        ctx: &Context,
        needs: SceneNeeds,
        settings: &crate::render::settings::RenderSettings,
    ) -> Result<Self> {
        let debug_view = settings.debug_view != crate::render::settings::DebugView::None;
        let (mode, backend) = (settings.mode, settings.backend);
        if mode == Mode::Path {
            return Self::path(ctx, needs, settings);
        }
        // A debug view traces no secondary rays.
        let wanted = if debug_view {
            Effects { shadows: false, reflections: false, refractions: false, ..settings.effects }
        } else {
            settings.effects
        };
        let d = Effects::default();
        let effects = Effects {
            shadows: wanted.shadows && needs.shadows,
            reflections: wanted.reflections && needs.reflections,
            refractions: wanted.refractions && needs.refractions,
            max_depth: d.max_depth,
            min_weight: d.min_weight,
            count_rays: d.count_rays,
        };
        let reference = settings.reference.is_some() && !debug_view;
        if settings.terms != 0 && (reference || debug_view) {
            bail!("the attribution terms replace neither the ambient reference nor a debug view");
        }
        let terms = settings.terms != 0;
        let ambient_visibility = AmbientMode::pick(settings, needs.scene_ambient) == AmbientMode::Traced
            && needs.ambient_occluders
            && !debug_view
            && !reference;
        use crate::render::settings::PrimaryVisibility as Pv;
        let visibility = if mode == Mode::Hybrid { settings.primary_visibility } else { Pv::Raster };
        let traces = mode == Mode::Rt
            || ambient_visibility
            || visibility != Pv::Raster
            || reference
            || terms
            || effects.shadows
            || effects.reflections
            || effects.refractions;
        let backend = if !traces {
            None
        } else {
            Some(pick_backend(backend, &ctx.rt, &ctx.caps.limits, &needs, software(ctx))?)
        };
        let luminance = settings.exposure_for(needs.scene_exposure).1.measures_luminance() && !debug_view;
        let secondary = backend.is_some() && (effects.shadows || effects.reflections || effects.refractions);
        let budget = settings.budget.is_some()
            && (secondary || settings.debug_view == crate::render::settings::DebugView::Selection);
        let shadow_fallback = budget
            && backend.is_some()
            && effects.shadows
            && needs.shadow_maps
            && settings.budget.is_some_and(|b| b.fallback == crate::render::budget::Fallback::Raster);
        Ok(ShadingConfig {
            inject: false,
            mode,
            effects,
            backend,
            debug_view,
            needs,
            luminance,
            budget,
            shadow_fallback,
            aa: settings.aa,
            edge_aa_tiled: settings.edge_aa_tiled,
            reference,
            terms,
            visibility,
            // Only the raster G-buffer pass (hybrid, raster or auto visibility) culls.
            occlusion: settings.occlusion_culling
                && ctx.caps.multi_draw_indirect
                && mode == Mode::Hybrid
                && visibility != Pv::Traced,
            glossy_temporal: settings.glossy_temporal,
            ambient_visibility,
            // Unless the attribution supplies the emitters' light (report/attribution.rs).
            ao_emitter_specular: ambient_visibility
                && needs.emitters
                && settings.terms & crate::gpu::shared::TERM_EMITTERS == 0,
        })
    }

    /// `--mode path`: the path tracer traces everything itself; none of the
    /// hybrid frame's effects, budget, reference or anti-aliasing exist.
    fn path(
        ctx: &Context,
        needs: SceneNeeds,
        settings: &crate::render::settings::RenderSettings,
    ) -> Result<Self> {
        if settings.debug_view != crate::render::settings::DebugView::None {
            bail!("--debug-view shows the G-buffer, which --mode path has not: use --mode hybrid or rt");
        }
        let backend = pick_backend(settings.backend, &ctx.rt, &ctx.caps.limits, &needs, software(ctx))?;
        Ok(ShadingConfig {
            inject: false,
            mode: Mode::Path,
            effects: Effects::NONE,
            backend: Some(backend),
            debug_view: false,
            needs,
            luminance: settings.exposure_for(needs.scene_exposure).1.measures_luminance(),
            budget: false,
            shadow_fallback: false,
            aa: AaMode::None,
            edge_aa_tiled: settings.edge_aa_tiled,
            reference: false,
            terms: false,
            visibility: crate::render::settings::PrimaryVisibility::Raster,
            occlusion: false,
            glossy_temporal: false,
            ambient_visibility: false,
            ao_emitter_specular: false,
        })
    }

    /// Why this backend (for the log).
    pub fn backend_reason(&self, ctx: &Context, requested: Backend) -> &'static str {
        match (self.backend, requested) {
            (None, _) if self.debug_view => "a debug view traces no rays",
            (None, _) => "no secondary effect needs rays",
            (Some(_), Backend::Auto)
                if software(ctx) && (ctx.rt.ray_query || ctx.rt.ray_tracing_pipeline) =>
            {
                "auto: a CPU (software) device, where the compute BVH tracer outruns the driver's ray tracing"
            }
            (Some(_), Backend::Auto) if ctx.rt.ray_query => "auto: the device supports ray queries",
            (Some(_), Backend::Auto) if ctx.rt.ray_tracing_pipeline => {
                "auto: no ray queries, the device offers ray-tracing pipelines"
            }
            (Some(_), Backend::Auto) => "auto: no ray-tracing extension, using the compute BVH fallback",
            (Some(_), _) => "requested with --backend",
        }
    }

    /// Specialization constants of glsl/common/integrator.glsl.
    pub fn specialization(&self) -> Vec<(u32, u32)> {
        let e = &self.effects;
        let on = self.backend.is_some();
        vec![
            (SPEC_SHADOWS, (on && e.shadows) as u32),
            (SPEC_REFLECTIONS, (on && e.reflections) as u32),
            (SPEC_REFRACTIONS, (on && e.refractions) as u32),
        ]
    }

    pub fn describe(&self) -> String {
        if self.mode == Mode::Path {
            let b = self.backend.map_or("none", Backend::name);
            return format!("mode Path, backend {b}: the path-traced ground truth");
        }
        let e = &self.effects;
        let on: Vec<&str> =
            [(e.shadows, "shadows"), (e.reflections, "reflections"), (e.refractions, "refractions")]
                .iter()
                .filter(|(b, _)| *b && self.backend.is_some())
                .map(|(_, n)| *n)
                .collect();
        let aa = if self.debug_view { "none (debug view)" } else { self.aa.name() };
        format!(
            "mode {:?}, backend {}, secondary effects: {}{}, aa {aa}",
            self.mode,
            self.backend.map_or("none", Backend::name),
            if on.is_empty() { "none".to_string() } else { on.join(", ") },
            if self.budget { " (per-object budget)" } else { "" }
        ) + if self.reference { ", ray-traced ambient reference" } else { "" }
            + if self.ambient_visibility { ", traced ambient visibility" } else { "" }
            + if self.terms { ", path-traced attribution terms" } else { "" }
            + match (self.mode, self.visibility) {
                (Mode::Rt | Mode::Path, _) => "",
                (_, crate::render::settings::PrimaryVisibility::Raster) => ", primary visibility raster",
                (_, crate::render::settings::PrimaryVisibility::Traced) => ", primary visibility traced",
                (_, crate::render::settings::PrimaryVisibility::Auto) => {
                    ", primary visibility auto (measured per view)"
                }
            }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn needs(triangles: u64, instances: u64) -> SceneNeeds {
        SceneNeeds {
            shadows: true,
            reflections: false,
            mirrors: false,
            glossy: false,
            refractions: false,
            shadow_maps: false,
            ambient_occluders: false,
            emitters: false,
            scene_ambient: None,
            scene_exposure: None,
            largest_primitive_triangles: triangles,
            instances,
        }
    }

    #[test]
    fn backends_respect_the_acceleration_structure_limits() {
        let rt = RtEnables { acceleration_structure: true, ray_query: true, ray_tracing_pipeline: true };
        let limits = Limits {
            max_image_dimension_2d: 16384,
            max_compute_work_group_count: [65535; 3],
            max_primitive_count: (1 << 24) - 1,
            max_instance_count: 1 << 24,
        };
        let fits = needs(1000, 10);
        assert_eq!(pick_backend(Backend::Auto, &rt, &limits, &fits, false).unwrap(), Backend::Query);
        assert_eq!(pick_backend(Backend::Auto, &rt, &limits, &fits, true).unwrap(), Backend::Compute);
        assert_eq!(pick_backend(Backend::Query, &rt, &limits, &fits, true).unwrap(), Backend::Query);
        assert_eq!(pick_backend(Backend::Pipeline, &rt, &limits, &fits, false).unwrap(), Backend::Pipeline);
        // One triangle over lavapipe's old 2^24 - 1 limit.
        let huge = needs(1 << 24, 10);
        assert_eq!(pick_backend(Backend::Auto, &rt, &limits, &huge, false).unwrap(), Backend::Compute);
        assert_eq!(pick_backend(Backend::Compute, &rt, &limits, &huge, false).unwrap(), Backend::Compute);
        for b in [Backend::Query, Backend::Pipeline] {
            let e = pick_backend(b, &rt, &limits, &huge, false).unwrap_err().to_string();
            assert!(e.contains("16777216 triangles") && e.contains("maxPrimitiveCount 16777215"), "{e}");
        }
        let many = needs(10, (1 << 24) + 1);
        let e = pick_backend(Backend::Query, &rt, &limits, &many, false).unwrap_err().to_string();
        assert!(e.contains("maxInstanceCount"), "{e}");
        let none = RtEnables { acceleration_structure: false, ray_query: false, ray_tracing_pipeline: false };
        assert_eq!(pick_backend(Backend::Auto, &none, &limits, &huge, false).unwrap(), Backend::Compute);
        assert!(pick_backend(Backend::Query, &none, &limits, &fits, false)
            .unwrap_err()
            .to_string()
            .contains("VK_KHR_ray_query"));
    }

    /// A rough material under a mirror-smooth coat needs the `specular` chain (the coat's mirror ray),
    /// under a glossy coat the `glossy` pass, under a rough coat no reflections at all.
    #[test]
    fn a_smooth_coat_needs_mirror_rays() {
        let dir = std::env::temp_dir().join(format!("hybrid_rt_coat_needs_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let needs_with = |coat_roughness: f32| {
            let path = dir.join(format!("coat_{coat_roughness}.toml"));
            let toml = format!(
                "[[material]]\nname = \"paint\"\nroughness = 0.9\nclearcoat = 1\n\
                 clearcoat_roughness = {coat_roughness}\n\n[[object]]\nname = \"floor\"\n\
                 primitive = \"plane\"\nsize = 4\nmaterial = \"paint\"\n"
            );
            std::fs::write(&path, toml).unwrap();
            SceneNeeds::of(&Scene::load(&path).unwrap())
        };
        let smooth = needs_with(0.05);
        assert!(smooth.mirrors && smooth.reflections && !smooth.glossy, "{smooth:?}");
        let glossy = needs_with(0.4);
        assert!(!glossy.mirrors && glossy.reflections && glossy.glossy, "{glossy:?}");
        let rough = needs_with(0.8);
        assert!(!rough.reflections, "{rough:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
