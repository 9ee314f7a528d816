//! PRT against closed forms: unshadowed = SH irradiance, the plane under a
//! sphere, interreflected ≥ shadowed, and the cache's invalidation.

use std::f64::consts::PI;

use glam::DVec3;

use super::*;
use crate::scene::primitives::{plane, uv_sphere};
use crate::scene::{Material, Mesh, Node, Object, Primitive, Transform};

/// A 4×4 plane (9 vertices, one at the origin, facing +Y) and a sphere of
/// radius `r` centred at (0, d, 0), both of albedo `albedo`.
fn plane_sphere(r: f32, d: f64, albedo: f32) -> Scene {
    let mut grid = plane(4.0, 4.0);
    // Subdivide to a 3×3 vertex grid so the origin is a vertex.
    let v0 = grid.vertices[0];
    let mut vertices = Vec::new();
    for z in 0..3 {
        for x in 0..3 {
            let mut v = v0;
            v.position = [-2.0 + 2.0 * x as f32, 0.0, -2.0 + 2.0 * z as f32];
            v.normal = [0.0, 1.0, 0.0];
            vertices.push(v);
        }
    }
    let mut indices = Vec::new();
    for z in 0..2u32 {
        for x in 0..2u32 {
            let a = z * 3 + x;
            // Counter-clockwise seen from +Y.
            indices.extend_from_slice(&[a, a + 3, a + 1, a + 1, a + 3, a + 4]);
        }
    }
    grid.vertices = vertices;
    grid.indices = indices;
    let sphere = uv_sphere(r, 32, 16);
    let mesh = |name: &str, p: Primitive| Mesh { name: name.into(), primitives: vec![p] };
    let node = |mesh: usize, t: DVec3| Node {
        name: format!("n{mesh}"),
        mesh: Some(mesh),
        object: Some(0),
        local: Transform { translation: t, ..Default::default() },
        ..Default::default()
    };
    let mut scene = Scene {
        meshes: vec![mesh("plane", grid), mesh("sphere", sphere)],
        materials: vec![Material {
            base_color: [albedo, albedo * 0.5, albedo * 0.25, 1.0],
            ..Default::default()
        }],
        nodes: vec![node(0, DVec3::ZERO), node(1, DVec3::new(0.0, d, 0.0))],
        roots: vec![0, 1],
        objects: vec![Object::default()],
        ..Default::default()
    };
    scene.update_world();
    scene
}

/// Radiance coefficients of a constant environment L.
fn constant_env(l: f64) -> ShCoeffs {
    let mut c = vec![[0.0; 3]; 9];
    c[0] = [l * (4.0 * PI).sqrt(); 3];
    ShCoeffs::from_coeffs(3, c).unwrap()
}

fn settings(mode: PrtMode, samples: u32) -> PrtSettings {
    PrtSettings { samples, ..PrtSettings::new(mode) }
}

/// The vertex at the plane's origin (index 4 of the first instance).
const ORIGIN_VERTEX: usize = 4;

/// Unshadowed transfer and SH irradiance are the same integral, so the
/// (64² directions: 32² missed by 0.5% at some normals)
/// ambient a E / pi (albedo 1) agrees within 1/255 under a constant
/// environment and under a directional one, on the plane and the sphere.
#[test]
fn unshadowed_equals_sh_irradiance() {
    let scene = plane_sphere(1.0, 2.0, 0.5);
    let t = compute(&scene, &settings(PrtMode::Unshadowed, 64)).unwrap();
    let (verts, _) = world_vertices(&scene, &static_instances(&scene));
    assert_eq!(t.vertex_count(), verts.len());
    // A sky-like environment: brighter above and towards +X, positive.
    let mut sky = constant_env(1.0).coeffs().to_vec();
    sky[2] = [0.6, 0.5, 0.4]; // y_1^0 ~ cos(theta from +Y)
    sky[3] = [0.3, 0.2, 0.1];
    let sky = ShCoeffs::from_coeffs(3, sky).unwrap();
    for env in [constant_env(1.0), sky] {
        let irr = env.irradiance();
        for (v, wv) in verts.iter().enumerate() {
            let prt = t.irradiance(v, &env);
            let sh = irr.eval(wv.n);
            for c in 0..3 {
                let d = (prt[c] - sh[c]).abs() / PI;
                assert!(d < 1.0 / 255.0, "vertex {v} n {}: prt {prt:?} sh {sh:?}", wv.n);
            }
        }
    }
}

/// Plane point under a sphere of radius r at height d, constant L: the
/// sphere hides a cap of half-angle asin(r/d) around the normal, so
/// E = pi L (1 - (r/d)^2). Tolerance: 4 standard deviations of plain Monte
/// Carlo with M = N² directions (stratification only lowers it), plus the
/// tessellation: the 32×16 sphere's faces lie between r cos²(pi/32) and r
/// from its centre.
#[test]
fn shadowed_plane_under_sphere() {
    let (r, d, l) = (1.0, 2.0, 1.0);
    let n = 64u32;
    let scene = plane_sphere(r as f32, d, 0.5);
    let t = compute(&scene, &settings(PrtMode::Shadowed, n)).unwrap();
    let s = r / d;
    let want = PI * l * (1.0 - s * s);
    let cos_c = (1.0 - s * s).sqrt();
    // Per-direction estimator X = 4 pi L max(0, n.w) V: E[X^2] = 4 pi L^2
    // ∫ cos² V = 8 pi² L² cos_c³ / 3.
    let var = 8.0 * PI * PI * l * l * cos_c.powi(3) / 3.0 - want * want;
    let mc = 4.0 * var.sqrt() / (n as f64);
    let s_min = s * (PI / 32.0).cos().powi(2);
    let tess = PI * l * (s * s - s_min * s_min);
    let got = t.irradiance(ORIGIN_VERTEX, &constant_env(l))[0];
    assert!(
        (got - want).abs() <= mc + tess,
        "E {got} vs pi L (1 - (r/d)^2) = {want} (tolerance {mc} MC + {tess} tessellation)"
    );
    // The unoccluded corners of the plane see (almost) the whole sky.
    let corner = t.irradiance(0, &constant_env(l))[0];
    assert!(corner > want, "corner {corner} vs origin {got}");
}

/// Interreflection only adds light (constant environment): every vertex's
/// irradiance is at least the shadowed one, and equal for albedo 0.
#[test]
fn interreflected_vs_shadowed() {
    for albedo in [0.8f32, 0.0] {
        let scene = plane_sphere(1.0, 1.5, albedo);
        let sh = compute(&scene, &settings(PrtMode::Shadowed, 12)).unwrap();
        let mut s = settings(PrtMode::Interreflected, 12);
        s.bounces = 2;
        let ir = compute(&scene, &s).unwrap();
        assert_eq!(ir.channels(), 3);
        let env = constant_env(1.0);
        let mut gained = 0.0f64;
        for v in 0..sh.vertex_count() {
            let (a, b) = (sh.irradiance(v, &env), ir.irradiance(v, &env));
            for c in 0..3 {
                if albedo == 0.0 {
                    assert_eq!(a[c] as f32, b[c] as f32, "albedo 0, vertex {v}");
                } else {
                    assert!(b[c] >= a[c] - 1e-6, "vertex {v}: {b:?} < {a:?}");
                }
                gained = gained.max(b[c] - a[c]);
            }
        }
        // With albedo the plane's origin sees the lit sphere's underside.
        assert_eq!(gained > 1e-3, albedo > 0.0, "albedo {albedo}: largest gain {gained}");
    }
}

/// A skinned or animated instance gets no transfer.
#[test]
fn animated_instances_are_not_static() {
    let mut scene = plane_sphere(1.0, 2.0, 0.5);
    assert_eq!(static_instances(&scene), vec![0, 1]);
    scene.animations.push(crate::scene::animation::Animation::new(
        "a".into(),
        vec![crate::scene::animation::AnimationChannel {
            node: 1,
            times: vec![0.0],
            interpolation: crate::scene::animation::Interpolation::Step,
            values: crate::scene::animation::Channel::Translation(vec![glam::Vec3::ZERO]),
        }],
    ));
    assert_eq!(static_instances(&scene), vec![0]);
    let t = compute(&scene, &settings(PrtMode::Unshadowed, 4)).unwrap();
    assert_eq!(t.first_vertex, vec![Some(0), None]);
    assert_eq!(t.vertex_count(), 9);
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hybrid-rt-prt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

use std::path::PathBuf;

/// The second run loads; a changed vertex, bands, samples, mode or
/// (interreflected) albedo recomputes; a truncated file recomputes.
#[test]
fn cache_hits_and_invalidates() {
    let dir = temp_dir("cache");
    let cache = PrtCache::new(Some(dir.clone()));
    let scene = plane_sphere(1.0, 2.0, 0.5);
    let s = settings(PrtMode::Shadowed, 6);
    let (a, o) = cache.get(&scene, &s).unwrap();
    assert_eq!(o, CacheOutcome::Computed);
    let (b, o) = cache.get(&scene, &s).unwrap();
    assert_eq!(o, CacheOutcome::Loaded);
    assert_eq!(a.data, b.data);
    assert_eq!(a.first_vertex, b.first_vertex);

    let mut moved = scene.clone();
    moved.meshes[1].primitives[0].vertices[7].position[1] += 0.01;
    assert_eq!(cache.get(&moved, &s).unwrap().1, CacheOutcome::Computed);
    for changed in [
        PrtSettings { bands: 4, ..s },
        PrtSettings { samples: 7, ..s },
        PrtSettings { mode: PrtMode::Unshadowed, ..s },
        PrtSettings { mode: PrtMode::Interreflected, ..s },
    ] {
        assert_eq!(cache.get(&scene, &changed).unwrap().1, CacheOutcome::Computed, "{changed:?}");
        assert_eq!(cache.get(&scene, &changed).unwrap().1, CacheOutcome::Loaded, "{changed:?}");
    }
    // Bounces and albedo only key interreflected transfer.
    assert_eq!(cache.get(&scene, &PrtSettings { bounces: 3, ..s }).unwrap().1, CacheOutcome::Loaded);
    let ir = PrtSettings { mode: PrtMode::Interreflected, ..s };
    let mut dark = scene.clone();
    dark.materials[0].base_color = [0.1, 0.1, 0.1, 1.0];
    assert_eq!(cache.get(&dark, &ir).unwrap().1, CacheOutcome::Computed);
    assert_eq!(cache.get(&scene, &PrtSettings { bounces: 2, ..ir }).unwrap().1, CacheOutcome::Computed);

    // Truncated, then garbage of the right length: recomputed, same data.
    let path = cache.path(cache::key(&scene, &s)).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let (c, o) = cache.get(&scene, &s).unwrap();
    assert_eq!((o, &c.data), (CacheOutcome::Computed, &a.data));
    let mut flipped = bytes.clone();
    flipped[40] ^= 0x55;
    std::fs::write(&path, &flipped).unwrap();
    assert_eq!(cache.get(&scene, &s).unwrap().1, CacheOutcome::Computed);
    assert_eq!(cache.get(&scene, &s).unwrap().1, CacheOutcome::Loaded);
    // No temporary files are left behind.
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(names.iter().all(|n| n.to_string_lossy().ends_with(".prt")), "{names:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn settings_are_checked() {
    let scene = plane_sphere(1.0, 2.0, 0.5);
    for bad in [
        PrtSettings { samples: 0, ..PrtSettings::new(PrtMode::Shadowed) },
        PrtSettings { bands: 9, ..PrtSettings::new(PrtMode::Shadowed) },
        PrtSettings { bounces: MAX_BOUNCES + 1, ..PrtSettings::new(PrtMode::Interreflected) },
    ] {
        assert!(compute(&scene, &bad).is_err(), "{bad:?}");
    }
    let e = format!(
        "{:#}",
        compute(&scene, &PrtSettings { samples: 0, ..PrtSettings::new(PrtMode::Shadowed) }).unwrap_err()
    );
    assert!(e.contains("--prt-samples"), "{e}");
}

/// The shadow rays' first-hit traversal agrees with the closest hit on
/// whether anything is hit (every vertex of the scene, every direction).
#[test]
fn any_hit_agrees_with_closest_hit() {
    let scene = plane_sphere(1.0, 1.5, 0.5);
    let statics = static_instances(&scene);
    let (verts, first) = world_vertices(&scene, &statics);
    let occ = transfer::Occluders::build(&scene, &statics, &first);
    let dirs = transfer::SampleSet::new(12, 1, 7);
    let mut hits = 0;
    for v in &verts {
        for d in &dirs.dirs {
            let any = occ.occluded(v, *d);
            assert_eq!(any, occ.trace(v, *d).is_some(), "vertex {:?} dir {d}", v.p);
            hits += any as usize;
        }
    }
    assert!(hits > 1000, "{hits} hits");
}
