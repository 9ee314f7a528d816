//! Deterministic scenes of a chosen size for `bench --scale` (issue 36): code, not checked-in data, so
//! any size exists on demand and every run sees the same triangles.
//!
//! - [`unique`]: about N unique triangles — a height field (`primitives::terrain`, every cell differs)
//!   plus a mirror sphere, so reflection rays trace the big tree as well as shadow rays.
//! - [`instanced`]: one small mesh placed K times on a jittered grid over a ground plane, each
//!   placement its own object (the budget heuristic sees K objects): instancing at scale, where a
//!   renderer must not copy the mesh K times.

use glam::{DVec3, Quat, Vec3};

use super::camera::Camera;
use super::primitives::{self, TERRAIN_MAX_CELLS};
use super::{Environment, Light, LightKind, Material, Mesh, Node, Object, ObjectProps, Scene, Transform};

/// The largest unique series size: a terrain of `TERRAIN_MAX_CELLS`² cells.
pub const UNIQUE_MAX_TRIANGLES: u64 = 2 * (TERRAIN_MAX_CELLS as u64) * (TERRAIN_MAX_CELLS as u64);
/// Instances of the instanced series: one per node and object, so bounded by what a host can hold.
pub const INSTANCED_MAX: u64 = 1 << 24;

/// The sphere of the unique series: 32 x 16 quads.
const SPHERE_SLICES: u32 = 32;
const SPHERE_STACKS: u32 = 16;

/// A scene of `triangles` unique triangles (within a cell row of the terrain and the sphere's 960).
pub fn unique(triangles: u64) -> anyhow::Result<Scene> {
    anyhow::ensure!(
        (1..=UNIQUE_MAX_TRIANGLES).contains(&triangles),
        "a generated unique scene holds 1 to {UNIQUE_MAX_TRIANGLES} triangles, not {triangles}"
    );
    let sphere = primitives::uv_sphere(12.0, SPHERE_SLICES, SPHERE_STACKS);
    let left = triangles.saturating_sub(sphere.indices.len() as u64 / 3).max(2);
    let cells = ((left as f64 / 2.0).sqrt().round() as u32).clamp(1, TERRAIN_MAX_CELLS);
    let mut s = base_scene(
        Vec3::new(0.0, 45.0, 160.0),
        Vec3::ZERO,
        vec![
            material("ground", [0.35, 0.45, 0.25], 0.0, 0.9),
            material("mirror", [0.95, 0.95, 0.95], 1.0, 0.0),
        ],
    );
    let mut terrain = primitives::terrain(400.0, 400.0, cells, cells, 30.0);
    terrain.material = 0;
    let mut ball = sphere;
    ball.material = 1;
    add_object(&mut s, "terrain", terrain, &[Transform::default()]);
    let at = Transform { translation: DVec3::new(0.0, 45.0, 60.0), ..Default::default() };
    add_object(&mut s, "ball", ball, &[at]);
    s.source = format!("(generated: {triangles} unique triangles)").into();
    s.finish();
    Ok(s)
}

/// A scene of `count` placements of one 12-triangle box (a "rock": rotated and scaled by a hash of its
/// index) on a square grid, over a ground plane.
pub fn instanced(count: u64) -> anyhow::Result<Scene> {
    anyhow::ensure!(
        (1..=INSTANCED_MAX).contains(&count),
        "a generated instanced scene holds 1 to {INSTANCED_MAX} instances, not {count}"
    );
    const SPACING: f64 = 3.0;
    let side = (count as f64).sqrt().ceil() as u64;
    let extent = side as f64 * SPACING;
    let mut s = base_scene(
        Vec3::new(0.0, 0.45, 0.75) * extent as f32 + Vec3::new(0.0, 4.0, 6.0),
        Vec3::ZERO,
        vec![material("ground", [0.5, 0.5, 0.45], 0.0, 0.8), material("rock", [0.6, 0.55, 0.5], 0.0, 0.5)],
    );
    let mut ground = primitives::plane(extent as f32 + 4.0, extent as f32 + 4.0);
    ground.material = 0;
    add_object(&mut s, "ground", ground, &[Transform::default()]);
    let mut rock = primitives::cube(1.0);
    rock.material = 1;
    let placements: Vec<Transform> = (0..count)
        .map(|k| {
            let h = hash(k);
            let unit = |shift: u32| ((h >> shift) & 0xFFFF) as f64 / 65535.0;
            let (i, j) = ((k % side) as f64, (k / side) as f64);
            Transform {
                translation: DVec3::new(
                    (i + 0.5 + 0.5 * (unit(0) - 0.5)) * SPACING - 0.5 * extent,
                    0.5,
                    (j + 0.5 + 0.5 * (unit(16) - 0.5)) * SPACING - 0.5 * extent,
                ),
                rotation: Quat::from_rotation_y((unit(32) * std::f64::consts::TAU) as f32),
                scale: Vec3::splat(0.6 + 0.8 * unit(48) as f32),
            }
        })
        .collect();
    add_object(&mut s, "rock", rock, &placements);
    s.source = format!("(generated: {count} instances)").into();
    s.finish();
    Ok(s)
}

/// A constant sky, a sun, one camera and `materials`.
fn base_scene(eye: Vec3, target: Vec3, materials: Vec<Material>) -> Scene {
    Scene {
        materials,
        // A fixed exposure, like the shipped scenes: the scale benches time the same passes at every size.
        environment: Environment {
            color: Vec3::new(0.45, 0.55, 0.75),
            exposure: Some(super::SceneExposure::Fixed(1.0)),
            ..Default::default()
        },
        lights: vec![Light {
            name: "sun".into(),
            kind: LightKind::Directional,
            color: Vec3::new(1.0, 0.95, 0.85),
            intensity: 3.0,
            position: DVec3::ZERO,
            direction: Vec3::new(-0.4, -1.0, -0.3).normalize(),
            range: None,
            casts_shadows: true,
            node: None,
        }],
        cameras: vec![Camera::look_at("overlook", eye, target, 55f32.to_radians(), 0.1)],
        ..Default::default()
    }
}

fn material(name: &str, rgb: [f32; 3], metallic: f32, roughness: f32) -> Material {
    Material {
        name: name.into(),
        base_color: [rgb[0], rgb[1], rgb[2], 1.0],
        metallic,
        roughness,
        ..Default::default()
    }
}

/// One mesh of `primitive`, a root node and an object per placement.
fn add_object(s: &mut Scene, name: &str, primitive: super::Primitive, placements: &[Transform]) {
    let mesh = s.meshes.len();
    s.meshes.push(Mesh { name: name.into(), primitives: vec![primitive] });
    s.nodes.reserve(placements.len());
    s.objects.reserve(placements.len());
    for (k, &local) in placements.iter().enumerate() {
        let object = s.objects.len();
        let label = if placements.len() == 1 { name.to_string() } else { format!("{name} {k}") };
        s.objects.push(Object { name: label.clone(), props: ObjectProps::default() });
        s.roots.push(s.nodes.len());
        s.nodes.push(Node {
            name: label,
            local,
            mesh: Some(mesh),
            object: Some(object),
            ..Default::default()
        });
    }
}

/// SplitMix64: a fixed, well-mixed jitter per index.
fn hash(k: u64) -> u64 {
    let mut z = k.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangles(s: &Scene) -> u64 {
        s.instances.iter().map(|i| s.meshes[i.mesh].primitives[i.primitive].indices.len() as u64 / 3).sum()
    }

    #[test]
    fn unique_scenes_hold_the_triangles_asked_for() {
        for n in [10_000u64, 100_000, 1_000_000] {
            let s = unique(n).unwrap();
            let got = triangles(&s);
            // Within one cell row (2 x cells triangles) of the request.
            let slack = 2.0 * (n as f64 / 2.0).sqrt() + 4.0;
            assert!((got as f64 - n as f64).abs() <= slack, "{n}: {got}");
            assert_eq!(s.instances.len(), 2);
            assert_eq!(s.cameras.len(), 1);
        }
        // Deterministic: the same size gives the same vertices.
        let (a, b) = (unique(20_000).unwrap(), unique(20_000).unwrap());
        assert_eq!(a.meshes[0].primitives[0].vertices, b.meshes[0].primitives[0].vertices);
        assert!(unique(0).is_err());
        assert!(unique(UNIQUE_MAX_TRIANGLES + 1).is_err());
    }

    #[test]
    fn instanced_scenes_place_one_mesh_count_times_as_objects() {
        for n in [1u64, 7, 1000] {
            let s = instanced(n).unwrap();
            assert_eq!(s.meshes.len(), 2, "ground and one rock mesh");
            assert_eq!(s.instances.len() as u64, n + 1);
            assert_eq!(s.objects.len() as u64, n + 1);
            assert_eq!(triangles(&s), 2 + 12 * n);
            // Every rock on the ground, inside the plane.
            let half = s.meshes[0].primitives[0].vertices.iter().map(|v| v.position[0]).fold(0.0, f32::max);
            for i in &s.instances[1..] {
                let p = i.world.w_axis.truncate();
                assert!(p.x.abs() < half as f64 && p.z.abs() < half as f64 && p.y == 0.5, "{p:?}");
            }
        }
        let (a, b) = (instanced(50).unwrap(), instanced(50).unwrap());
        assert!(a.instances.iter().zip(&b.instances).all(|(x, y)| x.world == y.world));
        assert!(instanced(0).is_err());
    }
}
