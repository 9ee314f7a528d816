//! The CPU tracer against brute force, edge cases of the watertight test
//! and the slab test.

use glam::Quat;

use super::*;
use crate::scene::primitives::{cube, uv_sphere};

struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    /// Uniform in [-1, 1)^3.
    fn v(&mut self) -> Vec3 {
        Vec3::new(self.f(), self.f(), self.f()) * 2.0 - 1.0
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.v();
            if v.length_squared() > 0.01 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

fn aabbs(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
    tris.iter().map(|t| Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) }).collect()
}

fn brute_force(tris: &[[Vec3; 3]], o: Vec3, d: Vec3, tmax: f32) -> Option<(u32, f32, f32, f32)> {
    let ray = WatertightRay::new(o, d);
    let mut best = None;
    let mut tmax = tmax;
    for (i, t) in tris.iter().enumerate() {
        if let Some((th, u, v)) = ray.intersect(t[0], t[1], t[2], tmax) {
            tmax = th;
            best = Some((i as u32, th, u, v));
        }
    }
    best
}

fn assert_finite(h: Option<(u32, f32, f32, f32)>) {
    if let Some((_, t, u, v)) = h {
        assert!(t.is_finite() && u.is_finite() && v.is_finite(), "{h:?}");
    }
}

/// Gives every group of positions closer than 1e-5 one bitwise-identical
/// value (the UV sphere's seam and south pole are not exactly shared).
fn weld(tris: &mut [[Vec3; 3]]) {
    let mut canon: Vec<Vec3> = Vec::new();
    for t in tris.iter_mut() {
        for p in t.iter_mut() {
            match canon.iter().find(|c| c.distance(*p) < 1e-5) {
                Some(c) => *p = *c,
                None => canon.push(*p),
            }
        }
    }
}

/// Closed double fan: `n` ring vertices (radius and height jittered when
/// `irregular`) joined to apexes at +-y: every apex is a fan of `n`
/// triangles around one vertex.
fn bipyramid(n: usize, irregular: bool, rng: &mut Rng) -> Vec<[Vec3; 3]> {
    let ring: Vec<Vec3> = (0..n)
        .map(|i| {
            let a = i as f32 / n as f32 * std::f32::consts::TAU;
            let (r, h) = if irregular { (0.5 + rng.f(), (rng.f() - 0.5) * 0.6) } else { (1.0, 0.0) };
            Vec3::new(a.cos() * r, h, a.sin() * r)
        })
        .collect();
    let (top, bottom) = (Vec3::Y, -Vec3::Y);
    (0..n).flat_map(|i| [[top, ring[(i + 1) % n], ring[i]], [bottom, ring[i], ring[(i + 1) % n]]]).collect()
}

/// Every distinct vertex and a few points on every edge.
fn vertex_and_edge_targets(tris: &[[Vec3; 3]], rng: &mut Rng) -> Vec<Vec3> {
    let mut out: Vec<Vec3> = Vec::new();
    for t in tris {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            if !out.contains(&a) {
                out.push(a);
            }
            out.push(a.lerp(b, 0.5));
            out.push(a.lerp(b, rng.f()));
        }
    }
    out
}

/// Rays from outside through `targets` (vertices, edge points) towards
/// interior points, and from outside to random interior points, must
/// all hit; through a target, no later than the target (the entry).
fn assert_closed(name: &str, tris: &[[Vec3; 3]], interior: impl Fn(&mut Rng) -> Vec3, convex: bool) {
    let mut rng = Rng(0x5eed ^ tris.len() as u64);
    let bvh = Bvh::build(&aabbs(tris));
    let targets = vertex_and_edge_targets(tris, &mut rng);
    let mut rays = 0;
    for &target in &targets {
        for _ in 0..6 {
            let q = interior(&mut rng);
            let o = target + (target - q).normalize() * (0.5 + 4.0 * rng.f());
            let d = target - o; // the target at t = 1
            let hit = traverse_closest(&bvh, tris, o, d, f32::INFINITY);
            let (_, t, _, _) = hit.unwrap_or_else(|| panic!("{name}: ray {o} -> {target} leaked"));
            assert!(t <= 1.0 + 1e-4, "{name}: ray {o} -> {target} entered late (t = {t})");
            if convex {
                assert!((t - 1.0).abs() <= 1e-4, "{name}: ray {o} -> {target} hit at t = {t}");
            }
            // Same distance up to rounding: through a shared vertex or
            // edge the incident triangles' t differ in the last bits, and
            // the traversal may stop at any of them.
            let brute = brute_force(tris, o, d, f32::INFINITY).unwrap();
            assert!((t - brute.1).abs() <= 1e-6 * brute.1, "{name}: {t} vs brute force {}", brute.1);
            rays += 1;
        }
    }
    for _ in 0..2000 {
        let o = rng.unit() * (3.0 + 3.0 * rng.f());
        let q = interior(&mut rng);
        assert!(traverse_closest(&bvh, tris, o, q - o, f32::INFINITY).is_some(), "{name}: {o} -> {q}");
        rays += 1;
    }
    eprintln!("{name}: {} triangles, {rays} rays, no leaks", tris.len());
}

#[test]
fn closed_meshes_never_leak() {
    let c = cube(2.0);
    let tris = triangle_positions(&c.vertices, &c.indices);
    assert_closed("cube", &tris, |r| r.v() * 0.9, true);

    let s = uv_sphere(1.0, 24, 12);
    let mut tris = triangle_positions(&s.vertices, &s.indices);
    weld(&mut tris);
    assert_closed("uv sphere", &tris, |r| r.v() * 0.5, true);

    let mut rng = Rng(3);
    let fan = bipyramid(9, false, &mut rng);
    assert_closed("regular double fan", &fan, |r| r.v() * 0.3, true);
    let fan = bipyramid(13, true, &mut rng);
    assert_closed("irregular double fan", &fan, |r| r.v() * 0.05, false);
}

#[test]
fn axis_aligned_rays_through_cube_edges_and_corners() {
    let c = cube(2.0);
    let tris = triangle_positions(&c.vertices, &c.indices);
    let bvh = Bvh::build(&aabbs(&tris));
    let coords = [-1.0, -0.5, 0.0, 0.25, 1.0];
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            for &a in &coords {
                for &b in &coords {
                    // Origin 4 units outside the face, ray along -+axis,
                    // through face interiors, edges and corners.
                    let mut o = Vec3::ZERO;
                    o[axis] = 5.0 * sign;
                    o[(axis + 1) % 3] = a;
                    o[(axis + 2) % 3] = b;
                    let mut d = Vec3::ZERO;
                    d[axis] = -sign;
                    let hit = traverse_closest(&bvh, &tris, o, d, f32::INFINITY);
                    assert_finite(hit);
                    let (_, t, _, _) = hit.unwrap_or_else(|| panic!("axis ray {o} {d} missed"));
                    assert_eq!(t, 4.0, "axis ray {o} {d}");
                    // -0.0 components behave like +0.0.
                    let d2 = Vec3::select(d.cmpeq(Vec3::ZERO), Vec3::splat(-0.0), d);
                    let hit2 = traverse_closest(&bvh, &tris, o, d2, f32::INFINITY);
                    assert_eq!(hit2.map(|h| h.1), Some(4.0));
                }
            }
        }
    }
}

#[test]
fn ray_aabb_handles_zero_direction_components() {
    let b = Aabb { min: Vec3::new(-1.0, -1.0, -1.0), max: Vec3::new(1.0, 2.0, 3.0) };
    let inv = |d: Vec3| d.recip();
    let inf = f32::INFINITY;
    // Along +z from below, inside the x/y slabs, on faces, on an edge.
    for (x, y) in [(0.0, 0.0), (-1.0, 0.0), (1.0, 2.0), (-1.0, -1.0), (0.5, 2.0)] {
        let o = Vec3::new(x, y, -5.0);
        assert_eq!(ray_aabb(o, inv(Vec3::Z), 0.0, inf, &b), Some(4.0), "{o}");
        assert_eq!(ray_aabb(o, inv(Vec3::new(-0.0, 0.0, 1.0)), 0.0, inf, &b), Some(4.0), "{o}");
        assert_eq!(ray_aabb(o, inv(-Vec3::Z), 0.0, inf, &b), None, "{o} pointing away");
        assert_eq!(ray_aabb(o, inv(Vec3::Z), 0.0, 3.9, &b), None, "{o} too short");
    }
    // Outside a slab the ray is parallel to: never.
    for o in [Vec3::new(1.0001, 0.0, -5.0), Vec3::new(0.0, -1.5, -5.0), Vec3::new(2.0, 3.0, 0.0)] {
        assert_eq!(ray_aabb(o, inv(Vec3::Z), 0.0, inf, &b), None, "{o}");
    }
    // Inside: entry at tmin.
    assert_eq!(ray_aabb(Vec3::ZERO, inv(Vec3::X), 0.0, inf, &b), Some(0.0));
    // Flat box (a quad at z = 0): perpendicular and in-plane rays.
    let flat = Aabb { min: Vec3::new(-1.0, -1.0, 0.0), max: Vec3::new(1.0, 1.0, 0.0) };
    assert_eq!(ray_aabb(Vec3::new(0.3, 0.2, 2.0), inv(-Vec3::Z), 0.0, inf, &flat), Some(2.0));
    assert_eq!(ray_aabb(Vec3::new(-3.0, 0.0, 0.0), inv(Vec3::X), 0.0, inf, &flat), Some(2.0));
    assert_eq!(ray_aabb(Vec3::new(-3.0, 0.0, 1e-7), inv(Vec3::X), 0.0, inf, &flat), None);
    // Empty boxes never hit, whatever the ray.
    for d in [Vec3::X, Vec3::new(1.0, -2.0, 0.5), Vec3::new(0.0, 0.0, -1.0)] {
        assert_eq!(ray_aabb(Vec3::ZERO, inv(d), 0.0, inf, &Aabb::EMPTY), None);
        let inverted = Aabb { min: Vec3::splat(1e30), max: Vec3::splat(-1e30) };
        assert_eq!(ray_aabb(Vec3::ZERO, inv(d), 0.0, inf, &inverted), None);
    }
    // Random rays with zeroed components: never NaN, agrees with a
    // reference computed on the clamped segment.
    let mut rng = Rng(11);
    for i in 0..20000 {
        let mut d = rng.v();
        d[i % 3] = 0.0;
        if i % 7 == 0 {
            d[(i + 1) % 3] = 0.0;
        }
        let mut o = rng.v() * 3.0;
        if i % 5 == 0 {
            o[i % 3] = if i % 2 == 0 { b.min[i % 3] } else { b.max[i % 3] };
            // on a face plane
        }
        if let Some(t) = ray_aabb(o, inv(d), 0.0, inf, &b) {
            assert!(t.is_finite() && t >= 0.0);
            let p = o + d * t;
            let slack = 1e-4 * (1.0 + t);
            assert!((p.cmpge(b.min - slack) & p.cmple(b.max + slack)).all(), "{o} {d} {t} {p}");
        } else if d != Vec3::ZERO {
            // A miss: no point of the box along the ray (sampled).
            let far = 20.0 / d.length();
            for s in 0..=200 {
                let p = o + d * (far * s as f32 / 200.0);
                assert!(!(p.cmpgt(b.min + 1e-3) & p.cmplt(b.max - 1e-3)).all(), "{o} {d} misses {p}");
            }
        }
    }
}

#[test]
fn barycentrics_reconstruct_the_hit_point() {
    let mut rng = Rng(5);
    for i in 0..20000 {
        let scale = [1.0, 1e-3, 1e3][i % 3];
        let tri = [rng.v() * scale, rng.v() * scale, rng.v() * scale];
        let (bu, bv) = (rng.f(), rng.f());
        let (bu, bv) = if bu + bv > 1.0 { (1.0 - bu, 1.0 - bv) } else { (bu, bv) };
        let target = tri[0] * (1.0 - bu - bv) + tri[1] * bu + tri[2] * bv;
        let o = target + rng.unit() * scale * (1.0 + 3.0 * rng.f());
        let d = (target - o) * (0.1 + 4.0 * rng.f());
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        if n.length() < 1e-3 * scale * scale || n.normalize().dot(d.normalize()).abs() < 0.05 {
            continue; // nearly degenerate or grazing: too ill-conditioned for 1e-5
        }
        let (t, u, v) = intersect_triangle(o, d, &tri, f32::INFINITY)
            .unwrap_or_else(|| panic!("ray {o} {d} missed an interior point of {tri:?}"));
        let on_ray = o + d * t;
        let from_bary = tri[0] * (1.0 - u - v) + tri[1] * u + tri[2] * v;
        let tol = 1e-5 * scale * 4.0;
        assert!(on_ray.distance(from_bary) <= tol, "{on_ray} vs {from_bary}");
        assert!(on_ray.distance(target) <= tol, "{on_ray} vs {target}");
        assert!((u - bu).abs() < 1e-3 && (v - bv).abs() < 1e-3, "({u}, {v}) vs ({bu}, {bv})");
        // Reversed winding: same t, u and v swap.
        let (t2, u2, v2) = intersect_triangle(o, d, &[tri[0], tri[2], tri[1]], f32::INFINITY).unwrap();
        assert!((t2 - t).abs() <= 1e-6 * t.abs() + 1e-12 && (u2 - v).abs() < 1e-5 && (v2 - u).abs() < 1e-5);
    }
    // Exact case: the hit at vertex 1 gives (u, v) = (1, 0).
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    assert_eq!(intersect_triangle(Vec3::new(1.0, 0.0, 1.0), -Vec3::Z, &tri, 9.0), Some((1.0, 1.0, 0.0)));
    assert_eq!(intersect_triangle(Vec3::new(0.0, 1.0, -2.0), Vec3::Z, &tri, 9.0), Some((2.0, 0.0, 1.0)));
    assert_eq!(intersect_triangle(Vec3::new(0.0, 1.0, -2.0), Vec3::Z, &tri, 2.0), None, "t == tmax");
    assert_eq!(intersect_triangle(Vec3::new(0.0, 1.0, 0.0), Vec3::Z, &tri, 9.0), None, "t == 0");
}

#[test]
fn degenerate_triangles_never_hit() {
    let p = Vec3::new(0.3, -0.2, 0.7);
    let degenerate = [
        [p, p, p],
        [p, p, p + Vec3::X],
        [Vec3::ZERO, Vec3::ONE, Vec3::ONE * 2.0],
        [Vec3::ZERO, Vec3::ONE * 2.0, Vec3::ONE],
        [Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 4.0, 6.0), Vec3::new(3.0, 6.0, 9.0)],
        [Vec3::new(-1.0, 0.5, 0.0), Vec3::new(1.0, 0.5, 0.0), Vec3::new(0.0, 0.5, 0.0)],
    ];
    let mut rng = Rng(9);
    for tri in &degenerate {
        for i in 0..5000 {
            // Random rays and rays aimed exactly at points of the segment.
            let target = match i % 3 {
                0 => tri[(i / 3) % 3],
                1 => tri[0].lerp(tri[2], rng.f()),
                _ => rng.v() * 2.0,
            };
            let o = target + rng.unit() * 3.0;
            let mut d = target - o;
            if i % 11 == 0 {
                d = Vec3::new(0.0, 0.0, d.z); // axis-aligned
                if i % 2 == 0 {
                    d = Vec3::new(0.0, 0.0, 0.0); // zero direction
                }
            }
            let h = intersect_triangle(o, d, tri, f32::INFINITY);
            assert_eq!(h, None, "degenerate {tri:?} hit by {o} {d}");
        }
    }
    // And inside a BVH (zero-area leaves): no hit, no NaN.
    let tris: Vec<[Vec3; 3]> = (0..300).map(|i| degenerate[i % degenerate.len()]).collect();
    let bvh = Bvh::build(&aabbs(&tris));
    for _ in 0..2000 {
        let o = rng.v() * 5.0;
        assert_eq!(traverse_closest(&bvh, &tris, o, rng.v(), f32::INFINITY), None);
    }
}

#[test]
fn edge_on_rays_miss_without_nan() {
    let mut rng = Rng(13);
    // Triangle in y = 0 and rays within that plane, through it.
    let tri = [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.5)];
    for _ in 0..5000 {
        let target = Vec3::new(rng.f() - 0.5, 0.0, rng.f() - 0.5);
        let mut o = target + rng.unit() * 4.0;
        o.y = 0.0;
        let h = intersect_triangle(o, target - o, &tri, f32::INFINITY);
        assert_eq!(h, None, "edge-on {o} -> {target}");
    }
    // Tilted plane x + y + z = 0 with exactly representable vertices:
    // in-plane rays along its edges' directions.
    let tri = [Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, -1.0), Vec3::new(-1.0, 0.0, 1.0)];
    for (o, d) in [
        (Vec3::new(-3.0, 3.0, 0.0), Vec3::new(1.0, -1.0, 0.0)),
        (Vec3::new(0.0, -4.0, 4.0), Vec3::new(0.0, 1.0, -1.0)),
        (Vec3::new(4.0, 0.0, -4.0), Vec3::new(-1.0, 0.0, 1.0)),
        (Vec3::new(-2.0, 1.0, 1.0), Vec3::new(2.0, -1.0, -1.0)),
    ] {
        assert_eq!(intersect_triangle(o, d, &tri, f32::INFINITY), None, "{o} {d}");
    }
    // Arbitrary in-plane rays: hits would have to come from rounding;
    // whatever is reported must be finite.
    for _ in 0..5000 {
        let (a, b) = (rng.f(), rng.f());
        let target = tri[0] * (1.0 - a * 0.5 - b * 0.5) + tri[1] * a * 0.5 + tri[2] * b * 0.5;
        let d = (tri[1] - tri[0]) * rng.v().x + (tri[2] - tri[0]) * rng.v().y;
        let h = intersect_triangle(target - d * 3.0, d, &tri, f32::INFINITY);
        assert_finite(h.map(|(t, u, v)| (0, t, u, v)));
    }
}

#[test]
fn traversal_matches_brute_force() {
    let mut rng = Rng(21);
    let tris: Vec<[Vec3; 3]> = (0..3000)
        .map(|_| {
            let c = rng.v() * 20.0;
            [c + rng.v(), c + rng.v(), c + rng.v()]
        })
        .collect();
    let bvh = Bvh::build(&aabbs(&tris));
    let mut hits = 0;
    for i in 0..5000 {
        let o = rng.v() * 30.0;
        let mut d = if i % 2 == 0 { rng.v() } else { rng.v() * 20.0 - o };
        if i % 10 == 0 {
            d[i % 3] = 0.0; // some axis-parallel rays
        }
        let tmax = if i % 4 == 0 { 10.0 + 20.0 * rng.f() } else { f32::INFINITY };
        let a = traverse_closest(&bvh, &tris, o, d, tmax);
        let b = brute_force(&tris, o, d, tmax);
        assert_finite(a);
        match (a, b) {
            (Some(a), Some(b)) => {
                assert!((a.1 - b.1).abs() <= 1e-5 * b.1, "{a:?} vs {b:?}");
                assert!(a.0 == b.0 || a.1 == b.1, "different triangle, not a tie: {a:?} vs {b:?}");
                hits += 1;
            }
            (a, b) => assert_eq!(a, b),
        }
    }
    assert!(hits > 1000, "{hits} hits");
}

#[test]
fn two_level_matches_brute_force() {
    let mut rng = Rng(31);
    let s = uv_sphere(1.0, 16, 8);
    let c = cube(1.5);
    let meshes: Vec<Vec<[Vec3; 3]>> = vec![
        triangle_positions(&s.vertices, &s.indices),
        triangle_positions(&c.vertices, &c.indices),
        (0..200)
            .map(|_| {
                let c = rng.v() * 2.0;
                [c + rng.v() * 0.3, c + rng.v() * 0.3, c + rng.v() * 0.3]
            })
            .collect(),
    ];
    let blases: Vec<Bvh> = meshes.iter().map(|m| Bvh::build(&aabbs(m))).collect();
    let worlds: Vec<(usize, Mat4)> = (0..40)
        .map(|i| {
            let rot = Quat::from_axis_angle(rng.unit(), rng.f() * 6.0);
            let scale = Vec3::new(0.5 + rng.f(), 0.5 + rng.f(), 0.5 + rng.f());
            (i % 3, Mat4::from_scale_rotation_translation(scale, rot, rng.v() * 15.0))
        })
        .collect();
    let instances: Vec<BlasInstance> = worlds
        .iter()
        .map(|&(m, w)| BlasInstance { bvh: &blases[m], tris: &meshes[m], world_to_object: w.inverse() })
        .collect();
    let boxes: Vec<Aabb> = worlds.iter().map(|&(m, w)| blases[m].root_bounds().transformed(&w)).collect();
    let tlas = Bvh::build(&boxes);
    tlas.validate(&boxes).unwrap();
    // Brute force in object space (same arithmetic as the traversal).
    let brute = |o: Vec3, d: Vec3| {
        let mut best: Option<(u32, u32, f32, f32, f32)> = None;
        for (i, inst) in instances.iter().enumerate() {
            let (oo, od) =
                (inst.world_to_object.transform_point3(o), inst.world_to_object.transform_vector3(d));
            let tmax = best.map_or(f32::INFINITY, |b| b.2);
            if let Some((p, t, u, v)) = brute_force(inst.tris, oo, od, tmax) {
                best = Some((i as u32, p, t, u, v));
            }
        }
        best
    };
    let mut hits = 0;
    for _ in 0..4000 {
        let o = rng.v() * 25.0;
        let d = rng.v() * 15.0 - o;
        let a = traverse_two_level(&tlas, &instances, o, d, f32::INFINITY);
        let b = brute(o, d);
        match (a, b) {
            (Some(a), Some(b)) => {
                assert!((a.2 - b.2).abs() <= 1e-5 * b.2, "{a:?} vs {b:?}");
                assert!((a.0, a.1) == (b.0, b.1) || a.2 == b.2, "{a:?} vs {b:?}");
                // World-space hit point from barycentrics.
                let (m, w) = worlds[a.0 as usize];
                let t = meshes[m][a.1 as usize].map(|p| w.transform_point3(p));
                let p = t[0] * (1.0 - a.3 - a.4) + t[1] * a.3 + t[2] * a.4;
                assert!(p.distance(o + d * a.2) <= 1e-4 * (1.0 + p.length()), "{p} vs {}", o + d * a.2);
                hits += 1;
            }
            (a, b) => assert_eq!(a, b),
        }
    }
    assert!(hits > 500, "{hits} hits");
}
