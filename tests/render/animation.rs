//! Rigid glTF animation: a frame rendered after moving the instances in
//! place (instance buffer rewritten, TLAS / compute top level rebuilt) equals
//! a frame of the same pose uploaded as static geometry, in every backend.
use crate::common;

use hybrid_rt::render::shading::Backend;
use hybrid_rt::render::{RenderSettings, Renderer};
use hybrid_rt::scene::animation::find_animation;
use hybrid_rt::scene::Scene;

#[test]
fn moved_instances_match_the_same_pose_uploaded_static() {
    let path = common::shared_asset("gltf/BoxAnimated/glTF/BoxAnimated.gltf");
    let loaded = Scene::load(&path).unwrap();
    let anim = find_animation(&loaded, "0").unwrap();
    let camera = loaded.cameras[0].clone();
    let extent = ash::vk::Extent2D { width: 160, height: 90 };

    let mut start = loaded.clone();
    start.animate(anim, 0.0);
    let mut posed = loaded.clone();
    posed.animate(anim, 1.3);
    let moved_any = start.instances.iter().zip(&posed.instances).any(|(a, b)| a.world != b.world);
    assert!(moved_any, "the animation does not move anything at t = 1.3");

    for backend in [Backend::Query, Backend::Pipeline, Backend::Compute] {
        let settings = RenderSettings { backend, ..Default::default() };
        let ctx = common::validated_context();
        // Dynamic: built at t = 0, then moved to t = 1.3.
        let mut r = Renderer::new(&ctx, &start, extent).unwrap();
        let before = r.render(&ctx, &start, &camera, &settings).unwrap();
        r.update_scene(&ctx, &posed).unwrap();
        let dynamic = r.render(&ctx, &posed, &camera, &settings).unwrap();
        r.destroy(&ctx);
        // Static: the pose uploaded as it is.
        let mut r = Renderer::new(&ctx, &posed, extent).unwrap();
        let baked = r.render(&ctx, &posed, &camera, &settings).unwrap();
        r.destroy(&ctx);
        common::assert_validation_clean(&ctx);

        let (max, frac) = hybrid_rt::image_diff::diff_stats(&dynamic.ldr, &baked.ldr, 4, 1);
        eprintln!("{backend:?}: moved vs static: max diff {max}, {:.3}% pixels > 1", frac * 100.0);
        assert!(max <= 1, "{backend:?}: moved instances differ from the static pose (max {max})");
        let (_, changed) = hybrid_rt::image_diff::diff_stats(&before.ldr, &dynamic.ldr, 4, 8);
        assert!(changed > 0.005, "{backend:?}: the image did not change when the instances moved");
    }
}
