//! The device-side LBVH (accel/lbvh.rs, glsl/lbvh/) builds exactly the host reference's tree: the same
//! sorted Morton keys and triangle order (a stable radix sort), the same hierarchy (Karras 2012) and
//! the same boxes (bottom up), node for node, over inputs that stress each step: one to three
//! triangles, many equal keys (ties split by position), a flat axis, and more radix blocks than the
//! scan's workgroup has invocations. The tree is valid for its triangles, and its SAH cost stays
//! within twice the binned builder's (an LBVH with one triangle per leaf is a worse tree, not a broken
//! one). Validation clean.
use crate::common;

use glam::Vec3;
use hybrid_rt::accel::bvh::Bvh;
use hybrid_rt::accel::lbvh;
use hybrid_rt::scene::Aabb;

fn soup(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut r = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| {
            let c = Vec3::new(r(), r(), r()) * 100.0;
            [c, c + Vec3::new(r(), r(), r()) * 2.0, c + Vec3::new(r(), r(), r()) * 2.0]
        })
        .collect()
}

fn aabbs(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
    tris.iter().map(|t| Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) }).collect()
}

#[test]
fn device_lbvh_is_the_host_reference_and_a_valid_tree() {
    let ctx = common::validated_context();
    let same = vec![[Vec3::ZERO, Vec3::X, Vec3::Y]; 300];
    let flat: Vec<[Vec3; 3]> =
        soup(500, 3).into_iter().map(|t| t.map(|v| v * Vec3::new(1.0, 1.0, 0.0))).collect();
    // 70,000 triangles: 274 radix blocks, more than the scan's 64 invocations.
    let inputs = [soup(1, 1), soup(2, 2), soup(3, 3), same, flat, soup(1000, 5), soup(70_000, 6)];
    for tris in &inputs {
        let n = tris.len();
        let dev = lbvh::build_on_device(&ctx, tris).unwrap_or_else(|e| panic!("{n} triangles: {e:#}"));
        let (keys, order, _) = lbvh::reference(tris);
        assert_eq!(dev.keys, keys, "{n} triangles: sorted keys");
        assert_eq!(dev.bvh.prim_indices, order, "{n} triangles: triangle order (stable sort)");
        let host = lbvh::reference_bvh(tris).unwrap();
        assert_eq!(dev.bvh.nodes.len(), 2 * n - 1, "{n} triangles");
        assert!(
            dev.bvh.nodes == host.nodes,
            "{n} triangles: the device's hierarchy or boxes differ from the host's"
        );
        dev.bvh.validate(&aabbs(tris)).unwrap_or_else(|e| panic!("{n} triangles: {e}"));
        assert_eq!(dev.pass_ms.len(), 4, "{n} triangles: timed steps");
    }
    let tris = &inputs[6];
    let (lbvh_sah, binned_sah) =
        (lbvh::reference_bvh(tris).unwrap().sah_cost(), Bvh::build(&aabbs(tris)).sah_cost());
    assert!(lbvh_sah <= 2.0 * binned_sah, "LBVH SAH {lbvh_sah} against binned {binned_sah}");
    ctx.finish().unwrap();
}
