//! Closed-form checks of the deferred lighting: a Lambertian quad lit by a
//! directional light at a known angle, and a point light's inverse-square
//! falloff. Radiance is read back linear (before tone mapping).
#![allow(clippy::needless_range_loop)] // per-channel loops read clearer with indices
use crate::common;

use glam::Vec3;
use hybrid_rt::render::RenderSettings;
use hybrid_rt::scene::*;

const ALBEDO: f32 = 0.5;
const W: u32 = 160;
const H: u32 = 90;

/// A 20 x 20 quad in the XZ plane, normal +Y, diffuse albedo 0.5, with IOR 1
/// so the Fresnel term (and with it any specular lobe) is practically zero.
fn quad_scene(light: Light) -> Scene {
    let s = 10.0;
    let v = |x: f32, z: f32| Vertex {
        position: [x, 0.0, z],
        normal: [0.0, 1.0, 0.0],
        uv: [0.0, 0.0],
        tangent: [1.0, 0.0, 0.0, 1.0],
    };
    let vertices = vec![v(-s, -s), v(-s, s), v(s, s), v(s, -s)];
    let mut bounds = Aabb::EMPTY;
    for p in &vertices {
        bounds.grow(Vec3::from(p.position));
    }
    let material = Material {
        name: "lambert".into(),
        base_color: [ALBEDO, ALBEDO, ALBEDO, 1.0],
        metallic: 0.0,
        roughness: 1.0,
        ior: 1.0,
        ..Default::default()
    };
    let mut scene = Scene {
        meshes: vec![Mesh {
            name: "quad".into(),
            primitives: vec![Primitive {
                vertices,
                indices: vec![0, 1, 2, 0, 2, 3],
                material: 0,
                bounds,
                skin: None,
            }],
        }],
        materials: vec![material],
        nodes: vec![Node { name: "quad".into(), mesh: Some(0), object: Some(0), ..Default::default() }],
        roots: vec![0],
        objects: vec![Object { name: "quad".into(), props: ObjectProps::default() }],
        lights: vec![light],
        environment: Environment { color: Vec3::ZERO, intensity: 0.0, ..Default::default() },
        ..Default::default()
    };
    scene.cameras.push(Camera::look_at("top", Vec3::new(0.0, 6.0, 0.0), Vec3::ZERO, 60f32.to_radians(), 0.1));
    scene.finish();
    scene
}

/// World point on y = 0 seen through pixel (x, y), using the same camera model.
fn pixel_to_ground(cam: &Camera, x: u32, y: u32) -> Vec3 {
    let (o, dir) = common::pixel_ray(cam, W, H, x, y);
    o + dir * (-o.y / dir.y)
}

fn render(scene: &Scene) -> hybrid_rt::render::FrameOutput {
    common::render_scene(scene, W, H, &RenderSettings::default())
}

fn assert_close(actual: f32, expected: f32, what: &str) {
    let rel = (actual - expected).abs() / expected.abs().max(1e-12);
    assert!(rel < 0.01, "{what}: got {actual}, expected {expected} (rel. error {:.4}%)", rel * 100.0);
}

#[test]
fn directional_light_matches_lambert_cosine_law() {
    let theta = 60f32.to_radians();
    let e = 3.0; // lux, perpendicular to the light
    let light = Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        color: Vec3::new(1.0, 0.5, 0.25),
        intensity: e,
        position: glam::DVec3::ZERO,
        direction: Vec3::new(theta.sin(), -theta.cos(), 0.0),
        range: None,
        casts_shadows: false,
        node: None,
    };
    let scene = quad_scene(light.clone());
    let out = render(&scene);
    for (x, y) in [(W / 2, H / 2), (10, 10), (W - 7, H - 3), (40, 70)] {
        let l = out.radiance(x, y);
        for c in 0..3 {
            let expected = ALBEDO / std::f32::consts::PI * e * light.color[c] * theta.cos();
            assert_close(l[c], expected, &format!("pixel ({x},{y}) channel {c}"));
        }
    }
}

#[test]
fn point_light_falls_off_with_inverse_square() {
    let h = 2.0;
    let intensity = 40.0; // candela
    let light = Light {
        name: "bulb".into(),
        kind: LightKind::Point,
        color: Vec3::ONE,
        intensity,
        position: Vec3::new(1.0, h, -0.5).as_dvec3(),
        direction: Vec3::NEG_Y,
        range: None,
        casts_shadows: false,
        node: None,
    };
    let scene = quad_scene(light.clone());
    let out = render(&scene);
    let cam = &scene.cameras[0];
    let mut values = Vec::new();
    for (x, y) in [(W / 2, H / 2), (20, 15), (W - 20, H - 10), (100, 30), (5, 80)] {
        let p = pixel_to_ground(cam, x, y);
        let d = light.position.as_vec3() - p;
        let dist = d.length();
        let cos = d.y / dist;
        let expected = ALBEDO / std::f32::consts::PI * intensity * cos / (dist * dist);
        let got = out.radiance(x, y)[1];
        assert_close(got, expected, &format!("pixel ({x},{y}) at {p}"));
        values.push(got);
    }
    // The falloff is real: the brightest and dimmest samples differ a lot.
    let (min, max) = values.iter().fold((f32::MAX, 0f32), |(a, b), v| (a.min(*v), b.max(*v)));
    assert!(max / min > 3.0, "expected strong falloff, got {min}..{max}");
}
