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

/// A buffer larger than the upload's staging bound arrives whole: every chunk at its offset (an upload
/// into the middle of a buffer included), nothing left of a chunk boundary.
#[test]
fn uploads_larger_than_the_staging_bound_arrive_whole() {
    use ash::vk;
    use gpu_allocator::MemoryLocation;
    use hybrid_rt::vk::{Buffer, STAGING_BYTES};
    let ctx = common::validated_context();
    let n = 2 * STAGING_BYTES + 12_345;
    let data: Vec<u8> = (0..n as u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8).collect();
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    let mut device = Buffer::with_data(&ctx, "big upload", &data, usage).unwrap();
    // Again at an offset: the last chunk straddles the first upload's chunk boundaries.
    let at = STAGING_BYTES as u64 - 7;
    let tail = &data[..STAGING_BYTES + 100];
    device.upload(&ctx, at, tail).unwrap();
    let mut host = Buffer::new(
        &ctx,
        "big readback",
        n as u64,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )
    .unwrap();
    ctx.one_shot("read back", |cmd| {
        let region = [vk::BufferCopy::default().size(n as u64)];
        unsafe { ctx.device.cmd_copy_buffer(cmd, device.raw, host.raw, &region) };
        Ok(())
    })
    .unwrap();
    let got = host.read().unwrap();
    let mut want = data.clone();
    want[at as usize..at as usize + tail.len()].copy_from_slice(tail);
    let first_bad = got.iter().zip(&want).position(|(a, b)| a != b);
    assert_eq!(first_bad, None, "byte {first_bad:?} differs");
    assert_eq!(got.len(), n);
    host.destroy(&ctx);
    device.destroy(&ctx);
    drop(ctx);
}
