//! Skinned animation on the GPU: the skinning pass + per-frame refit of the
//! skinned acceleration structures give the same image as the same pose
//! skinned on the CPU and uploaded as static geometry; refit equals rebuild;
//! a long animated run neither leaks GPU memory nor trips validation.
use crate::common;

use hybrid_rt::accel::dynamic::RebuildPolicy;
use hybrid_rt::image_diff::diff_stats;
use hybrid_rt::render::shading::Backend;
use hybrid_rt::render::{RenderSettings, Renderer};
use hybrid_rt::scene::animation::find_animation;
use hybrid_rt::scene::Scene;

use common::BACKENDS;

fn load(model: &str) -> (Scene, usize) {
    let scene = Scene::load(&common::shared_asset(model)).unwrap();
    let anim = find_animation(&scene, "0").unwrap();
    (scene, anim)
}

fn posed(scene: &Scene, anim: usize, t: f32) -> Scene {
    let mut s = scene.clone();
    s.animate(anim, t);
    s
}

#[test]
fn gpu_skinning_matches_the_pose_baked_on_the_cpu() {
    let extent = ash::vk::Extent2D { width: 160, height: 90 };
    for (model, t) in
        [("gltf/CesiumMan/glTF/CesiumMan.gltf", 1.1), ("gltf/RiggedFigure/glTF/RiggedFigure.gltf", 0.6)]
    {
        let (loaded, anim) = load(model);
        let start = posed(&loaded, anim, 0.0);
        let target = posed(&loaded, anim, t);
        let camera = loaded.cameras[0].clone();
        let baked = target.bake_skinning();
        assert!(baked.instances.iter().all(|i| i.skinned.is_none()));
        for backend in BACKENDS {
            let settings = RenderSettings { backend, ..Default::default() };
            let ctx = common::validated_context();
            // Dynamic: uploaded at t = 0, then skinned + refit on the GPU.
            let mut r = Renderer::new(&ctx, &start, extent).unwrap();
            let first = r.render(&ctx, &start, &camera, &settings).unwrap();
            r.update_scene(&ctx, &target).unwrap();
            assert_eq!(r.update.counts, [1, 0], "{model} {backend:?}: one skinned structure refit");
            let dynamic = r.render(&ctx, &target, &camera, &settings).unwrap();
            r.destroy(&ctx);
            // Static: the CPU pose uploaded as ordinary geometry.
            let mut r = Renderer::new(&ctx, &baked, extent).unwrap();
            let reference = r.render(&ctx, &baked, &camera, &settings).unwrap();
            r.destroy(&ctx);
            common::assert_validation_clean(&ctx);

            let (max, frac) = diff_stats(&dynamic.ldr, &reference.ldr, 4, 0);
            eprintln!(
                "{model} {backend:?}: GPU skinned vs CPU baked: max {max}, {:.3}% pixels differ",
                frac * 100.0
            );
            assert_eq!(max, 0, "{model} {backend:?}: {:.3}% pixels differ (max {max})", frac * 100.0);
            let (_, moved) = diff_stats(&first.ldr, &dynamic.ldr, 4, 8);
            assert!(moved > 0.003, "{model} {backend:?}: the pose did not change the image");
        }
    }
}

#[test]
fn refit_and_rebuild_give_the_same_image() {
    let (loaded, anim) = load("gltf/Fox/glTF/Fox.gltf");
    let camera = loaded.cameras[0].clone();
    let extent = ash::vk::Extent2D { width: 160, height: 90 };
    for backend in BACKENDS {
        let settings = RenderSettings { backend, ..Default::default() };
        let ctx = common::validated_context();
        let mut frames = Vec::new();
        for (policy, expect) in [(RebuildPolicy::NEVER, [1, 0]), (RebuildPolicy::ALWAYS, [0, 1])] {
            let mut scene = posed(&loaded, anim, 0.0);
            let mut r = Renderer::new(&ctx, &scene, extent).unwrap();
            r.update.policy = policy;
            r.render(&ctx, &scene, &camera, &settings).unwrap();
            // Several refits in a row: errors would accumulate.
            for i in 1..=6 {
                scene.animate(anim, 0.25 * i as f32);
                r.update_scene(&ctx, &scene).unwrap();
                assert_eq!(r.update.counts, expect, "{backend:?} {policy:?}");
            }
            frames.push(r.render(&ctx, &scene, &camera, &settings).unwrap());
            r.destroy(&ctx);
        }
        common::assert_validation_clean(&ctx);
        let (max, frac) = diff_stats(&frames[0].ldr, &frames[1].ldr, 4, 0);
        eprintln!("{backend:?}: refit vs rebuild: max diff {max}, {:.3}% pixels differ", frac * 100.0);
        assert_eq!(max, 0, "{backend:?}: refit and rebuild differ (max {max}, {:.3}%)", frac * 100.0);
    }
}

#[test]
fn two_thousand_animated_frames_keep_memory_flat_and_validation_clean() {
    let (loaded, anim) = load("gltf/CesiumMan/glTF/CesiumMan.gltf");
    let camera = loaded.cameras[0].clone();
    let extent = ash::vk::Extent2D { width: 32, height: 18 };
    let ctx = common::validated_context();
    let mut scene = posed(&loaded, anim, 0.0);
    let mut r = Renderer::new(&ctx, &scene, extent).unwrap();
    // Half the run refits the ray-query BLAS, half the compute BVH (the
    // switch rebuilds the structures once).
    let mut memory = Vec::new();
    for i in 0..2000 {
        let backend = if i < 1000 { Backend::Auto } else { Backend::Compute };
        scene.animate(anim, i as f32 / 60.0);
        r.update_scene(&ctx, &scene).unwrap();
        let out = r.render(&ctx, &scene, &camera, &RenderSettings { backend, ..Default::default() }).unwrap();
        assert!(out.hdr.iter().all(|v| v.is_finite()), "frame {i}: non-finite pixel");
        if [100, 999, 1100, 1999].contains(&i) {
            memory.push(ctx.allocated_bytes());
        }
    }
    eprintln!("GPU memory (bytes) at frames 100, 999, 1100, 1999: {memory:?}");
    assert_eq!(memory[0], memory[1], "GPU memory grew over 900 ray-query frames");
    assert_eq!(memory[2], memory[3], "GPU memory grew over 900 compute-BVH frames");
    r.destroy(&ctx);
    common::assert_validation_clean(&ctx);
}
