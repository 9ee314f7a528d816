//! Every allocation failure while a renderer is created and renders its
//! first frame is an error that leaves nothing behind: each failure point is
//! injected in turn (`Context::alloc_fault`), and the validated context
//! counts leaked objects when the device is destroyed.
use crate::common;

use ash::vk::Extent2D;
use hybrid_rt::render::shading::Backend;
use hybrid_rt::render::{RenderSettings, Renderer};
use hybrid_rt::scene::Scene;

/// Creates a renderer and renders one frame with the n-th allocation
/// failing; Ok(true) when no allocation failed (n is past the last one).
fn attempt(scene: &Scene, backend: Backend, n: u64) -> bool {
    let ctx = common::validated_context();
    ctx.alloc_fault.arm(n);
    let settings = RenderSettings { backend, ..Default::default() };
    let result = Renderer::new(&ctx, scene, Extent2D { width: 32, height: 18 }).and_then(|mut r| {
        let frame = r.render(&ctx, scene, &scene.cameras[0], &settings);
        r.destroy(&ctx);
        frame
    });
    ctx.alloc_fault.arm(0);
    match result {
        Ok(_) => true,
        Err(e) => {
            let msg = format!("{e:#}");
            assert!(msg.contains("injected"), "allocation {n}: unexpected error {msg}");
            false
        }
    }
    // Dropping `ctx` destroys the device: a leaked object fails here.
}

#[test]
fn every_allocation_failure_leaks_nothing() {
    // The default scene (static, textured environment) and a skinned model
    // (updatable BLASes, GPU refit of the compute BVH and its top level).
    let default = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    let skinned = Scene::load(&common::shared_asset("gltf/RiggedFigure/glTF/RiggedFigure.gltf")).unwrap();
    for (scene, backend) in [
        (&default, Backend::Query),
        (&default, Backend::Pipeline),
        (&default, Backend::Compute),
        (&skinned, Backend::Query),
        (&skinned, Backend::Compute),
    ] {
        let mut n = 1;
        while !attempt(scene, backend, n) {
            n += 1;
            assert!(n < 1000, "{backend:?}: still failing after 1000 injected failures");
        }
        eprintln!("{backend:?}: {} allocation failure points, none leaks", n - 1);
        assert!(n > 10, "{backend:?}: only {} allocations: is the fault hook reached?", n - 1);
    }
}
