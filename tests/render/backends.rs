//! Three ray backends, one image: ray query, ray-tracing pipeline and the
//! compute BVH tracer render the same scenes; they must agree pairwise.
//!
//! Tolerance, asserted per pair: on the analytic scenes the images are
//! identical up to 1/255 in any channel of any pixel (IDENTICAL); elsewhere
//! at most 0.5% of the pixels may differ by more than 2/255 in any channel
//! (NEAR: edges of alpha cut-outs and grazing hits, where the traversals'
//! float rounding legitimately picks a different triangle). The fraction and
//! the maximum difference are printed for every pair.
//!
//! Every backend renders with its own fresh renderer and context: a backend
//! that wrote nothing would otherwise show the previous backend's image.
use crate::common;

use common::scenes::*;

use hybrid_rt::app::GpuOptions;
use hybrid_rt::render::shading::{AaMode, Backend, Mode};
use hybrid_rt::render::{FrameOutput, RenderSettings, Renderer};
use hybrid_rt::scene::Scene;

use common::BACKENDS;

fn render_all(scene: &Scene, w: u32, h: u32, mode: Mode, aa: AaMode) -> Vec<(Backend, FrameOutput)> {
    let mut out = Vec::new();
    for b in BACKENDS {
        let ctx = common::validated_context();
        let mut r = Renderer::new(&ctx, scene, ash::vk::Extent2D { width: w, height: h }).unwrap();
        let s = RenderSettings { backend: b, mode, aa, ..Default::default() };
        let frame = r.render(&ctx, scene, &scene.cameras[0], &s).unwrap();
        assert_eq!(r.shading_config().unwrap().backend, Some(b));
        assert!(frame.all_finite(), "{b:?}: NaN/Inf");
        r.destroy(&ctx);
        out.push((b, frame));
    }
    out
}

/// How close two backends' images must be.
#[derive(Clone, Copy, Debug)]
enum Bound {
    /// No channel of any pixel differs by more than 1/255.
    Identical,
    /// At most 0.5% of pixels differ by more than 2/255, none by more than
    /// NEAR_MAX (a share alone would pass a few pixels that are plain wrong;
    /// measured on lavapipe: 5/255 at most, TransmissionTest's compute vs query).
    Near,
}
use Bound::*;

const NEAR_MAX: u8 = 16;

fn assert_agree(name: &str, frames: &[(Backend, FrameOutput)], bound: Bound) {
    for i in 0..frames.len() {
        for j in i + 1..frames.len() {
            let (a, fa) = &frames[i];
            let (b, fb) = &frames[j];
            let (max, frac) = hybrid_rt::image_diff::diff_stats(&fa.ldr, &fb.ldr, 4, 2);
            let psnr = hybrid_rt::image_diff::psnr_rgb8(&fa.ldr, &fb.ldr, 4, None);
            eprintln!(
                "{name}: {a:?} vs {b:?}: {:.3}% pixels differ by > 2/255, max difference {max}/255, PSNR {psnr:.1} dB",
                frac * 100.0
            );
            match bound {
                Identical => assert!(max <= 1, "{name}: {a:?} vs {b:?}: max difference {max}/255 > 1/255"),
                Near => {
                    assert!(frac <= 0.005, "{name}: {a:?} vs {b:?}: {:.3}% pixels differ", frac * 100.0);
                    assert!(
                        max <= NEAR_MAX,
                        "{name}: {a:?} vs {b:?}: max difference {max}/255 > {NEAR_MAX}/255"
                    );
                }
            }
        }
    }
}

#[test]
fn analytic_scenes_agree_across_backends() {
    let cases = [
        ("agreement", agreement()),
        ("shadow", shadow_scene(Frame::IDENTITY, opaque_occluder())),
        ("glass shadow", shadow_scene(Frame::IDENTITY, glass_occluder([1.0, 0.3, 0.1]))),
        ("mirror", mirror_scene([0.9, 0.6, 0.3], [0.8, 0.5, 0.25])),
        ("facing mirrors", facing_mirrors()),
    ];
    for (name, text) in cases {
        let scene = common::scene_from_toml(&format!("backends_{}", name.replace(' ', "_")), &text);
        assert_agree(name, &render_all(&scene, 160, 90, Mode::Hybrid, AaMode::Edge), Identical);
    }
}

#[test]
fn pure_ray_tracing_agrees_across_backends() {
    let scene = common::scene_from_toml("backends_rt", &agreement());
    // Before anti-aliasing: where a camera ray meets an edge two triangles
    // share, query and compute may store different primitives (the same
    // shading), and the edge filter's coverage walk then differs at a few
    // silhouette pixels (19/255 at most here). Known, not yet fixed.
    assert_agree("agreement (pure RT)", &render_all(&scene, 160, 90, Mode::Rt, AaMode::None), Identical);
}

#[test]
fn sponza_with_spheres_agrees_across_backends() {
    let scene = Scene::load(&common::repo_path("assets/sponza_spheres.toml")).unwrap();
    assert_agree("sponza_spheres", &render_all(&scene, 160, 90, Mode::Hybrid, AaMode::Edge), Near);
}

/// GlassVaseFlowers: alpha-masked leaves seen through and beside a glass vase (a real asset where query
/// and compute once differed on 0.2 % of pixels, max 77/255; 1/255 at 320x320 since).
#[test]
fn alpha_mask_and_transmission_models_agree_across_backends() {
    for rel in [
        "gltf/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf",
        "gltf/TransmissionTest/glTF/TransmissionTest.gltf",
        "gltf/GlassVaseFlowers/glTF/GlassVaseFlowers.gltf",
    ] {
        let scene = Scene::load(&common::shared_asset(rel)).unwrap();
        assert_agree(rel, &render_all(&scene, 160, 90, Mode::Hybrid, AaMode::Edge), Near);
    }
}

/// The pipeline backend's image on a context made with `opts` (checked by
/// `check`) must be its image on the default context: renders `agreement()`.
fn pipeline_matches_default_context(
    name: &str,
    opts: GpuOptions,
    check: fn(&hybrid_rt::vk::Context) -> bool,
) {
    let scene = common::scene_from_toml(name, &agreement());
    let ctx = common::validated(opts.context().unwrap());
    assert!(check(&ctx) && ctx.rt.ray_tracing_pipeline);
    let settings = RenderSettings { backend: Backend::Pipeline, ..Default::default() };
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: 160, height: 90 }).unwrap();
    let frame = r.render(&ctx, &scene, &scene.cameras[0], &settings).unwrap();
    assert_eq!(r.shading_config().unwrap().backend, Some(Backend::Pipeline));
    r.destroy(&ctx);
    common::assert_validation_clean(&ctx);
    drop(ctx);
    let reference = common::render_scene(&scene, 160, 90, &settings);
    assert_agree(name, &[(Backend::Pipeline, frame), (Backend::Pipeline, reference)], Identical);
}

/// Drivers that offer the ray-tracing pipeline but no ray queries (NVIDIA's
/// on some machines): with VK_KHR_ray_query left off, the pipeline backend
/// must not touch it (validation would name a shader or call that does) and
/// renders the image it renders with the extension on. (Seen failing with
/// the frame's passes taking their ray-query variants on that device.)
#[test]
fn the_pipeline_backend_runs_without_ray_queries() {
    let opts = GpuOptions { validation: true, disable_ray_query: true, ..Default::default() };
    pipeline_matches_default_context("backends_noquery", opts, |ctx| !ctx.rt.ray_query);
}

/// Drivers without rayTracingPipelineTraceRaysIndirect: the pipeline
/// backend's compacted pass (specular) launches one ray-generation
/// invocation per pixel instead of one per listed pixel, the spare ones
/// finding no entry (render/kernel.rs); the image is the indirect launch's.
#[test]
fn the_pipeline_backend_runs_without_indirect_launches() {
    let opts = GpuOptions { validation: true, disable_trace_rays_indirect: true, ..Default::default() };
    pipeline_matches_default_context("backends_noindirect", opts, |ctx| !ctx.caps.trace_rays_indirect);
}

/// Debian 12's stock lavapipe has no ray-tracing extension: with them
/// switched off the program must pick the compute backend, create no
/// acceleration structure, and still produce the ray-traced image.
#[test]
fn without_ray_tracing_extensions_the_compute_backend_runs() {
    let scene = common::scene_from_toml("backends_nort", &agreement());
    let ctx = common::validated(
        GpuOptions { validation: true, disable_ray_tracing: true, ..Default::default() }.context().unwrap(),
    );
    assert!(ctx.accel.is_none() && ctx.rt_pipeline.is_none());
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: 160, height: 90 }).unwrap();
    let frame = r.render(&ctx, &scene, &scene.cameras[0], &RenderSettings::default()).unwrap();
    assert_eq!(r.shading_config().unwrap().backend, Some(Backend::Compute));
    r.destroy(&ctx);
    drop(ctx);

    // Same image as the ray-query backend on the RT-enabled device.
    let reference = common::render_scene(
        &scene,
        160,
        90,
        &RenderSettings { backend: Backend::Query, ..Default::default() },
    );
    assert_agree(
        "no-rt compute vs query",
        &[(Backend::Compute, frame), (Backend::Query, reference)],
        Identical,
    );

    // Asking for a hardware backend there is a clear error, not a crash.
    let ctx = common::validated(
        GpuOptions { validation: true, disable_ray_tracing: true, ..Default::default() }.context().unwrap(),
    );
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: 32, height: 18 }).unwrap();
    let err = r
        .render(
            &ctx,
            &scene,
            &scene.cameras[0],
            &RenderSettings { backend: Backend::Query, ..Default::default() },
        )
        .err()
        .expect("query backend without the extension must fail");
    assert!(format!("{err:#}").contains("ray_query"), "{err:#}");
    r.destroy(&ctx);
}
