//! The scene's GPU memory breakdown (`GpuScene::memory`, logged after every upload, issue 36 item 5)
//! adds up: vertices (the skinned instances' deformed copies included) and indices at their exact
//! sizes, textures at least their base level and at most twice it (mips add a third, plus alignment),
//! and no more in all than the allocator holds.
use crate::common;

use hybrid_rt::gpu::GpuScene;
use hybrid_rt::scene::Scene;

#[test]
fn scene_memory_breakdown_matches_what_was_uploaded() {
    let path = common::shared_asset("gltf/CesiumMan/glTF/CesiumMan.gltf");
    let scene = Scene::load(&path).unwrap();
    let ctx = common::validated_context();
    let mut gpu = GpuScene::upload(&ctx, &scene).unwrap();
    let m = gpu.memory();
    let prims = || scene.meshes.iter().flat_map(|mesh| &mesh.primitives);
    let skinned: usize = scene
        .instances
        .iter()
        .filter(|i| i.skinned.is_some())
        .map(|i| scene.meshes[i.mesh].primitives[i.primitive].vertices.len())
        .sum();
    assert!(skinned > 0, "CesiumMan is skinned");
    let vertices: usize = prims().map(|p| p.vertices.len()).sum::<usize>() + skinned;
    assert_eq!(m.vertices, 48 * vertices as u64, "{m:?}");
    assert_eq!(m.indices, 4 * prims().map(|p| p.indices.len()).sum::<usize>() as u64, "{m:?}");
    let base: u64 = scene.textures.iter().map(|t| t.width as u64 * t.height as u64 * 4).sum();
    assert!(
        base > 0 && m.textures >= base && m.textures <= 2 * base,
        "textures {} for {base} B of texels",
        m.textures
    );
    assert!(m.environment > 0 && m.other > 0, "{m:?}");
    assert!(
        m.total() <= ctx.allocated_bytes(),
        "{} B in use, {} allocated",
        m.total(),
        ctx.allocated_bytes()
    );
    let per_triangle = m.geometry_per_triangle(scene.triangle_count());
    assert_eq!(per_triangle, (m.vertices + m.indices) as f64 / scene.triangle_count() as f64);
    assert!(m
        .describe(scene.triangle_count())
        .contains(&format!("geometry {per_triangle:.1} B per triangle")));
    gpu.destroy(&ctx);
    common::assert_validation_clean(&ctx);
}
