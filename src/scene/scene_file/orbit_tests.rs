//! Unit tests of scene-file orbits (`orbit = { center, axis, period }`): the
//! analytic circle, their errors, and orbits beside merged glTF animations.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};

use super::tests::{error_of, object_world, shared, write};
use super::SCENE_ANIMATION;
use crate::scene::animation::{find_animation, Interpolation};
use crate::scene::Scene;

/// Two orbits: a rotated, scaled cube about +Y (8 s) and a sphere about
/// an oblique axis (4 s: two turns per loop of the scene animation).
const ORBITS: &str = r#"
[[object]]
name = "still"
primitive = "plane"

[[object]]
name = "cube"
primitive = "cube"
translation = [3, 1, 0.5]
rotation_deg = [0, 30, 0]
scale = [1, 2, 1]
orbit = { center = [1, 1, 0], period = 8.0 }

[[object]]
name = "ball"
primitive = "sphere"
translation = [0, 2, -2]
orbit = { center = [0.5, 0, -1], axis = [1, 1, 0], period = 4.0 }
"#;

fn assert_close(got: Vec3, expected: Vec3, what: &str) {
    let error = (got - expected).length();
    assert!(error <= 1e-4 * expected.length().max(1.0), "{what}: {got} vs {expected} (error {error})");
}

#[test]
fn orbits_follow_the_analytic_circle() {
    let mut scene = Scene::load(&write("orbits", "scene.toml", ORBITS)).unwrap();
    assert_eq!(scene.animations.len(), 1);
    let anim = &scene.animations[0];
    assert_eq!((anim.name.as_str(), anim.duration, anim.channels.len()), (SCENE_ANIMATION, 8.0, 2));
    for c in &anim.channels {
        c.check().unwrap();
        assert_eq!(c.interpolation, Interpolation::Linear);
        assert_eq!(scene.nodes[c.node].children.len(), 1, "channels target the pivots");
    }
    assert_eq!(scene.roots.len(), 3);
    let index = find_animation(&scene, SCENE_ANIMATION).unwrap();

    // (object, translation, centre, unit axis, period)
    let orbits = [
        (1, Vec3::new(3.0, 1.0, 0.5), Vec3::new(1.0, 1.0, 0.0), Vec3::Y, 8.0f32),
        (2, Vec3::new(0.0, 2.0, -2.0), Vec3::new(0.5, 0.0, -1.0), Vec3::new(1.0, 1.0, 0.0).normalize(), 4.0),
    ];
    // Before any animation the scene is posed as the file says.
    let unmoved = Mat4::from_scale_rotation_translation(
        Vec3::new(1.0, 2.0, 1.0),
        Quat::from_rotation_y(30f32.to_radians()),
        orbits[0].1,
    );
    assert!(object_world(&scene, 1).abs_diff_eq(unmoved, 1e-5), "{}", object_world(&scene, 1));
    // As loaded (no animation applied yet).
    let rests = orbits.map(|o| object_world(&scene, o.0));
    for ((object, translation, center, axis, period), rest) in orbits.into_iter().zip(rests) {
        // Quarter periods are keys; 0.3 and 1.55 periods lie between keys
        // (slerp about a fixed axis stays on the circle) and in a later lap.
        for fraction in [0.0f32, 0.25, 0.5, 0.75, 1.0, 0.3, 1.55] {
            let t = fraction * period;
            scene.animate(index, t);
            let turn = Quat::from_axis_angle(axis, std::f32::consts::TAU * fraction);
            let expected = center + turn * (translation - center);
            let world = object_world(&scene, object);
            assert_close(world.w_axis.truncate(), expected, &format!("object {object} at t = {t}"));
            // The object turns with its orbit (like a moon showing one face).
            let about_center =
                Mat4::from_translation(center) * Mat4::from_quat(turn) * Mat4::from_translation(-center);
            assert!(world.abs_diff_eq(about_center * rest, 1e-4), "object {object} at t = {t}: {world}");
        }
    }
    // The plane without an orbit never moves.
    scene.animate(index, 3.0);
    assert_eq!(object_world(&scene, 0), Mat4::IDENTITY);
}

#[test]
fn orbit_errors_name_file_object_and_key() {
    let object =
        |orbit: &str| format!("[[object]]\nname = \"ball\"\nprimitive = \"sphere\"\norbit = {{ {orbit} }}\n");
    let cases = [
        ("center = [0, 0, 0], period = 0", "orbit.period must be positive and finite (got 0)"),
        ("center = [0, 0, 0], period = -2", "orbit.period must be positive and finite (got -2)"),
        ("center = [0, 0, 0], period = inf", "orbit.period must be positive and finite (got inf)"),
        ("center = [0, 0, 0], period = nan", "orbit.period must be positive and finite (got NaN)"),
        ("center = [0, 0, 0], axis = [0, 0, 0], period = 1", "orbit.axis must not be zero"),
        ("center = [0, 0, 0], axis = [0, nan, 0], period = 1", "orbit.axis must be finite"),
        ("center = [0, inf, 0], period = 1", "orbit.center must be finite"),
        ("center = [0, 0, 0]", "orbit needs `period`"),
        ("period = 1", "orbit needs `center`"),
    ];
    for (i, (orbit, expected)) in cases.iter().enumerate() {
        let err = error_of(&format!("orbit-{i}"), &object(orbit));
        assert!(
            err.contains("scene.toml:2: object 'ball': ") && err.contains(expected),
            "expected '{expected}' with file, line and object in: {err}"
        );
    }
    // Unknown orbit keys are rejected by the parser, with their line.
    let err = error_of("orbit-unknown", &object("center = [0, 0, 0], period = 1, phase_deg = 90"));
    assert!(err.contains("scene.toml") && err.contains("line 4") && err.contains("phase_deg"), "{err}");
    // Periods that do not divide the longest one cannot share its loop.
    let text = format!(
        "{}[[object]]\nname = \"odd\"\nprimitive = \"cube\"\norbit = {{ center = [0, 0, 0], period = 3 }}\n",
        object("center = [0, 0, 0], period = 8")
    );
    let err = error_of("orbit-periods", &text);
    assert!(
        err.contains(
            "scene.toml:6: object 'odd': orbit.period 3 s does not divide the longest orbit period 8 s"
        ),
        "{err}"
    );
    let text = format!(
        "{}[[object]]\nname = \"fast\"\nprimitive = \"cube\"\norbit = {{ center = [0, 0, 0], period = 1e-3 }}\n",
        object("center = [0, 0, 0], period = 8")
    );
    let err = error_of("orbit-fast", &text);
    assert!(err.contains("object 'fast': orbit.period 0.001 s makes 8000 turns"), "{err}");
}

#[test]
fn orbits_beside_merged_gltf_animations() {
    let box_path = shared("gltf/BoxAnimated/glTF/BoxAnimated.gltf");
    let text = format!(
        r#"
[[object]]
name = "box"
gltf = "{box_path}"
translation = [5, 0, 0]
orbit = {{ center = [0, 0, 0], period = 6 }}

[[object]]
name = "ball"
primitive = "sphere"
translation = [0, 0, 2]
orbit = {{ center = [0, 0, 0], axis = [1, 0, 0], period = 3 }}
"#
    );
    let mut scene = Scene::load(&write("orbit-gltf", "scene.toml", &text)).unwrap();
    let alone = Scene::load(Path::new(&box_path)).unwrap();
    // The glTF's animations keep their indices; the orbits come after.
    let names: Vec<&str> = scene.animations.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, [format!("box/{}", alone.animations[0].name).as_str(), SCENE_ANIMATION]);
    assert_eq!(find_animation(&scene, SCENE_ANIMATION).unwrap(), 1);
    assert_eq!(scene.animations[1].duration, 6.0);
    let positions = |s: &Scene| {
        let world = s.world_matrices();
        s.instances.iter().map(|i| (i.object, world[i.node].w_axis.truncate())).collect::<Vec<_>>()
    };
    let rest = positions(&scene);

    // The box's own animation moves only the box's parts, in place.
    scene.animate(0, 1.3);
    let boxed = positions(&scene);
    assert!(rest.iter().zip(&boxed).any(|(a, b)| a.0 == 0 && a.1 != b.1));
    assert!(rest.iter().zip(&boxed).all(|(a, b)| a.0 == 0 || a == b));

    // Half the box's period: the whole model is across the centre (the
    // merged root at -5), and the ball has made one full turn (period 3).
    scene.animate(1, 3.0);
    let box_root = scene.nodes.iter().position(|n| n.name == "box").unwrap();
    assert_close(
        scene.world_matrices()[box_root].w_axis.truncate().as_vec3(),
        Vec3::new(-5.0, 0.0, 0.0),
        "box root",
    );
    assert_close(object_world(&scene, 1).w_axis.truncate(), Vec3::new(0.0, 0.0, 2.0), "ball");
    // A quarter of the ball's period about +X: +Z turns to -Y.
    scene.animate(1, 0.75);
    assert_close(object_world(&scene, 1).w_axis.truncate(), Vec3::new(0.0, -2.0, 0.0), "ball");
}
