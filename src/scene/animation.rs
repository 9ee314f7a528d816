//! Rigid glTF node animation: keyframed translation, rotation and scale
//! channels sampled as the glTF 2.0 spec prescribes (Appendix C), written to
//! the nodes' local transforms. Skinning and morph targets are not supported.

use anyhow::{bail, Result};
use glam::{Quat, Vec3, Vec4};

use super::Scene;

/// How values between two keyframes are computed (glTF sampler interpolation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The value of the previous key holds until the next one.
    Step,
    /// Linear for vectors, shortest-path slerp for rotations.
    Linear,
    /// Cubic Hermite spline; values are stored as [in-tangent, value,
    /// out-tangent] triplets per key.
    CubicSpline,
}

/// Keyframe values of one channel: one per key, or three per key
/// ([in-tangent, value, out-tangent], as in the glTF spec) for
/// [`Interpolation::CubicSpline`].
#[derive(Clone, Debug, PartialEq)]
pub enum Channel {
    Translation(Vec<Vec3>),
    Rotation(Vec<Quat>),
    Scale(Vec<Vec3>),
}

impl Channel {
    pub fn len(&self) -> usize {
        match self {
            Channel::Translation(v) | Channel::Scale(v) => v.len(),
            Channel::Rotation(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One animated property of one node (index into `Scene::nodes`).
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationChannel {
    pub node: usize,
    /// Key times in seconds, non-decreasing.
    pub times: Vec<f32>,
    pub interpolation: Interpolation,
    pub values: Channel,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    pub name: String,
    pub channels: Vec<AnimationChannel>,
    /// Latest key time of all channels (the timeline starts at 0).
    pub duration: f32,
}

impl Animation {
    /// An animation with `duration` computed from its channels.
    pub fn new(name: String, channels: Vec<AnimationChannel>) -> Self {
        let duration = channels.iter().filter_map(|c| c.times.last().copied()).fold(0.0, f32::max);
        Self { name, channels, duration }
    }
}

impl AnimationChannel {
    /// Number of values each key has (3 for cubic splines).
    pub fn values_per_key(&self) -> usize {
        match self.interpolation {
            Interpolation::CubicSpline => 3,
            _ => 1,
        }
    }

    /// Whether the channel can be sampled: at least one key, finite
    /// non-decreasing times and the matching number of values.
    pub fn check(&self) -> Result<()> {
        if self.times.is_empty() {
            bail!("has no keyframes");
        }
        if let Some(i) = self.times.iter().position(|t| !t.is_finite()) {
            bail!("key time {i} is not finite ({})", self.times[i]);
        }
        if let Some(i) = self.times.windows(2).position(|w| w[1] < w[0]) {
            bail!(
                "key times are not increasing: {} follows {} at key {}",
                self.times[i + 1],
                self.times[i],
                i + 1
            );
        }
        let expected = self.times.len() * self.values_per_key();
        if self.values.len() != expected {
            bail!(
                "has {} output values for {} keys ({:?} needs {expected})",
                self.values.len(),
                self.times.len(),
                self.interpolation
            );
        }
        Ok(())
    }

    /// Translation sampled at `t`, if this is a (well-formed) translation channel.
    pub fn sample_translation(&self, t: f32) -> Option<Vec3> {
        match &self.values {
            Channel::Translation(v) => self.sample_vec3(v, t),
            _ => None,
        }
    }

    /// Scale sampled at `t`, if this is a (well-formed) scale channel.
    pub fn sample_scale(&self, t: f32) -> Option<Vec3> {
        match &self.values {
            Channel::Scale(v) => self.sample_vec3(v, t),
            _ => None,
        }
    }

    /// Unit rotation sampled at `t`, if this is a (well-formed) rotation channel.
    pub fn sample_rotation(&self, t: f32) -> Option<Quat> {
        let Channel::Rotation(v) = &self.values else { return None };
        let q = match self.locate(t, v.len())? {
            Key::At(k) => v[k],
            Key::Between { k, s, dt } => match self.interpolation {
                Interpolation::Step => v[k],
                Interpolation::Linear => slerp(v[k], v[k + 1], s),
                Interpolation::CubicSpline => Quat::from_vec4(hermite(
                    Vec4::from(v[3 * k + 1]),
                    Vec4::from(v[3 * k + 2]),
                    Vec4::from(v[3 * k + 4]),
                    Vec4::from(v[3 * k + 3]),
                    s,
                    dt,
                )),
            },
        };
        Some(Vec4::from(q).try_normalize().map_or(Quat::IDENTITY, Quat::from_vec4))
    }

    fn sample_vec3(&self, v: &[Vec3], t: f32) -> Option<Vec3> {
        Some(match self.locate(t, v.len())? {
            Key::At(k) => v[k],
            Key::Between { k, s, dt } => match self.interpolation {
                Interpolation::Step => v[k],
                Interpolation::Linear => v[k].lerp(v[k + 1], s),
                Interpolation::CubicSpline => {
                    hermite(v[3 * k + 1], v[3 * k + 2], v[3 * k + 4], v[3 * k + 3], s, dt)
                }
            },
        })
    }

    /// Which key (for cubic splines: which triplet's value) applies at `t`.
    /// None when the channel is malformed (see [`AnimationChannel::check`]).
    fn locate(&self, t: f32, value_count: usize) -> Option<Key> {
        let times = &self.times;
        if times.is_empty() || value_count != times.len() * self.values_per_key() {
            return None;
        }
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let at = |k: usize| Some(Key::At(if cubic { 3 * k + 1 } else { k }));
        let last = times.len() - 1;
        if t.is_nan() || t <= times[0] {
            return at(0);
        }
        if t >= times[last] {
            return at(last);
        }
        // times[k] <= t < times[k + 1]
        let k = times.partition_point(|&x| x <= t) - 1;
        let dt = times[k + 1] - times[k];
        if dt <= 0.0 {
            return at(k + 1);
        }
        let s = ((t - times[k]) / dt).clamp(0.0, 1.0);
        Some(Key::Between { k, s, dt })
    }
}

enum Key {
    /// Exactly one stored value (index into the value array).
    At(usize),
    /// Between key `k` and `k + 1`, `s` in [0, 1] across an interval `dt` long.
    Between { k: usize, s: f32, dt: f32 },
}

/// Shortest-path spherical interpolation, normalized.
fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    a.slerp(b, s).normalize()
}

/// glTF cubic Hermite spline between value `v0` (out-tangent `b0`) and value
/// `v1` (in-tangent `a1`); tangents are scaled by the key interval `dt`.
fn hermite<T>(v0: T, b0: T, v1: T, a1: T, s: f32, dt: f32) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let (s2, s3) = (s * s, s * s * s);
    v0 * (2.0 * s3 - 3.0 * s2 + 1.0)
        + b0 * (dt * (s3 - 2.0 * s2 + s))
        + v1 * (-2.0 * s3 + 3.0 * s2)
        + a1 * (dt * (s3 - s2))
}

impl Scene {
    /// Poses the scene at `time` seconds of `animation` (looping; zero length shows time 0) and calls
    /// [`Scene::update_world`]. Channels on missing nodes and malformed ones are ignored; an unknown
    /// animation index leaves the scene as it is.
    pub fn animate(&mut self, animation: usize, time: f32) {
        let Some(anim) = self.animations.get(animation) else {
            log::warn!("animate: no animation {animation} (the scene has {})", self.animations.len());
            return;
        };
        let t = if anim.duration > 0.0 && time.is_finite() { time.rem_euclid(anim.duration) } else { 0.0 };
        for c in &anim.channels {
            let Some(node) = self.nodes.get_mut(c.node) else { continue };
            match &c.values {
                Channel::Translation(_) => {
                    if let Some(v) = c.sample_translation(t) {
                        node.local.translation = v.as_dvec3();
                    }
                }
                Channel::Rotation(_) => {
                    if let Some(q) = c.sample_rotation(t) {
                        node.local.rotation = q;
                    }
                }
                Channel::Scale(_) => {
                    if let Some(v) = c.sample_scale(t) {
                        node.local.scale = v;
                    }
                }
            }
        }
        self.update_world();
    }
}

/// The animation named by `name_or_index`: an index into `Scene::animations`
/// or an exact animation name.
pub fn find_animation(scene: &Scene, name_or_index: &str) -> Result<usize> {
    if let Ok(i) = name_or_index.trim().parse::<usize>() {
        if i < scene.animations.len() {
            return Ok(i);
        }
    }
    if let Some(i) = scene.animations.iter().position(|a| a.name == name_or_index) {
        return Ok(i);
    }
    if scene.animations.is_empty() {
        bail!("{}: no animation '{name_or_index}': the scene has no animations", scene.source.display());
    }
    let available: Vec<String> =
        scene.animations.iter().enumerate().map(|(i, a)| format!("{i}: '{}'", a.name)).collect();
    bail!(
        "{}: no animation '{name_or_index}'; available (index: name): {}",
        scene.source.display(),
        available.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Node;
    use std::path::{Path, PathBuf};

    const EPS: f32 = 1e-5;

    fn channel(interpolation: Interpolation, times: &[f32], values: Channel) -> AnimationChannel {
        AnimationChannel { node: 0, times: times.to_vec(), interpolation, values }
    }

    fn translations(interpolation: Interpolation, times: &[f32], values: &[[f32; 3]]) -> AnimationChannel {
        channel(interpolation, times, Channel::Translation(values.iter().map(|&v| Vec3::from(v)).collect()))
    }

    fn close(a: impl Into<glam::DVec3>, b: impl Into<glam::DVec3>) -> bool {
        (a.into() - b.into()).length() < 1e-4
    }

    fn same_rotation(a: Quat, b: Quat) -> bool {
        a.dot(b).abs() > 1.0 - 1e-5
    }

    #[test]
    fn step_holds_the_previous_key() {
        let c = translations(Interpolation::Step, &[0.0, 1.0, 2.0], &[[0.0; 3], [1.0, 2.0, 3.0], [5.0; 3]]);
        c.check().unwrap();
        assert_eq!(c.sample_translation(0.0), Some(Vec3::ZERO));
        assert_eq!(c.sample_translation(0.99), Some(Vec3::ZERO));
        assert_eq!(c.sample_translation(1.0), Some(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(c.sample_translation(1.7), Some(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(c.sample_translation(2.0), Some(Vec3::splat(5.0)));
    }

    #[test]
    fn linear_midpoint_and_clamping_outside_the_keys() {
        let c = translations(Interpolation::Linear, &[1.0, 3.0], &[[0.0, 0.0, 0.0], [2.0, 4.0, -6.0]]);
        assert!(close(c.sample_translation(2.0).unwrap(), Vec3::new(1.0, 2.0, -3.0)));
        assert!(close(c.sample_translation(1.5).unwrap(), Vec3::new(0.5, 1.0, -1.5)));
        // Before the first key: the first value; after the last: the last.
        assert_eq!(c.sample_translation(0.0), Some(Vec3::ZERO));
        assert_eq!(c.sample_translation(-5.0), Some(Vec3::ZERO));
        assert_eq!(c.sample_translation(10.0), Some(Vec3::new(2.0, 4.0, -6.0)));
        // The wrong kind of sample is None, never a panic.
        assert_eq!(c.sample_rotation(2.0), None);
        assert_eq!(c.sample_scale(2.0), None);
    }

    #[test]
    fn single_key_is_constant() {
        for interpolation in [Interpolation::Step, Interpolation::Linear] {
            let c = translations(interpolation, &[0.5], &[[1.0, 2.0, 3.0]]);
            for t in [0.0, 0.5, 9.0] {
                assert_eq!(c.sample_translation(t), Some(Vec3::new(1.0, 2.0, 3.0)));
            }
        }
    }

    #[test]
    fn cubic_spline_with_zero_tangents_is_smoothstep() {
        let z = [0.0; 3];
        let c = translations(
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[[9.0; 3], [0.0; 3], z, z, [1.0, 2.0, 4.0], [9.0; 3]],
        );
        c.check().unwrap();
        for s in [0.0f32, 0.1, 0.25, 0.5, 0.8, 1.0] {
            let smooth = s * s * (3.0 - 2.0 * s);
            let got = c.sample_translation(2.0 * s).unwrap();
            assert!(close(got, Vec3::new(1.0, 2.0, 4.0) * smooth), "s = {s}: {got}");
        }
        // Outside the keys: the values, not the tangents.
        assert_eq!(c.sample_translation(-1.0), Some(Vec3::ZERO));
        assert_eq!(c.sample_translation(3.0), Some(Vec3::new(1.0, 2.0, 4.0)));
    }

    #[test]
    fn cubic_spline_tangents_are_scaled_by_the_key_interval() {
        // Value 0 -> 0 with out-tangent 1 (unit slope per second) over a
        // 2 s interval: p(s) = dt * (s^3 - 2 s^2 + s); at s = 0.5, 0.25.
        let c = translations(
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[[0.0; 3], [0.0; 3], [1.0, 0.0, 0.0], [0.0; 3], [0.0; 3], [0.0; 3]],
        );
        assert!(close(c.sample_translation(1.0).unwrap(), Vec3::new(0.25, 0.0, 0.0)));
        // A straight line expressed by its tangents is reproduced exactly.
        let line = translations(
            Interpolation::CubicSpline,
            &[1.0, 3.0],
            &[[1.0; 3], [0.0; 3], [1.0; 3], [1.0; 3], [2.0; 3], [1.0; 3]],
        );
        for t in [1.0, 1.3, 2.0, 2.9] {
            assert!(close(line.sample_translation(t).unwrap(), Vec3::splat(t - 1.0)), "t = {t}");
        }
    }

    #[test]
    fn slerp_midpoint_of_0_and_90_degrees_is_45() {
        let q0 = Quat::IDENTITY;
        let q1 = Quat::from_rotation_y(90f32.to_radians());
        let c = channel(Interpolation::Linear, &[0.0, 1.0], Channel::Rotation(vec![q0, q1]));
        let mid = c.sample_rotation(0.5).unwrap();
        assert!(same_rotation(mid, Quat::from_rotation_y(45f32.to_radians())), "{mid}");
        assert!((mid.length() - 1.0).abs() < EPS);
        let quarter = c.sample_rotation(0.25).unwrap();
        assert!(same_rotation(quarter, Quat::from_rotation_y(22.5f32.to_radians())), "{quarter}");
    }

    #[test]
    fn slerp_takes_the_shortest_path() {
        // -q1 is the same rotation as q1; the interpolation must not take the
        // 270 degree way round.
        let q0 = Quat::IDENTITY;
        let q1 = Quat::from_rotation_y(90f32.to_radians());
        let c = channel(Interpolation::Linear, &[0.0, 1.0], Channel::Rotation(vec![q0, -q1]));
        let mid = c.sample_rotation(0.5).unwrap();
        assert!(same_rotation(mid, Quat::from_rotation_y(45f32.to_radians())), "{mid}");
        // q and -q as the two keys: no rotation at all in between.
        let q = Quat::from_rotation_x(1.0);
        let c = channel(Interpolation::Linear, &[0.0, 1.0], Channel::Rotation(vec![q, -q]));
        for t in [0.25, 0.5, 0.75] {
            assert!(same_rotation(c.sample_rotation(t).unwrap(), q));
        }
    }

    #[test]
    fn step_and_cubic_rotations_are_unit() {
        let q1 = Quat::from_rotation_z(1.0);
        let c = channel(Interpolation::Step, &[0.0, 1.0], Channel::Rotation(vec![Quat::IDENTITY, q1]));
        assert_eq!(c.sample_rotation(0.9), Some(Quat::IDENTITY));
        assert!(same_rotation(c.sample_rotation(1.0).unwrap(), q1));
        let zero = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        let c = channel(
            Interpolation::CubicSpline,
            &[0.0, 1.0],
            Channel::Rotation(vec![zero, Quat::IDENTITY, zero, zero, q1, zero]),
        );
        for t in [0.0, 0.3, 0.5, 0.7, 1.0] {
            let q = c.sample_rotation(t).unwrap();
            assert!((q.length() - 1.0).abs() < EPS, "t = {t}: {q}");
        }
        assert!(same_rotation(c.sample_rotation(1.0).unwrap(), q1));
    }

    #[test]
    fn malformed_channels_are_reported_and_never_sampled() {
        let c = translations(Interpolation::CubicSpline, &[0.0, 1.0], &[[0.0; 3], [1.0; 3]]);
        assert!(c.check().unwrap_err().to_string().contains("needs 6"));
        assert_eq!(c.sample_translation(0.5), None);
        let c = translations(Interpolation::Linear, &[1.0, 0.0], &[[0.0; 3], [1.0; 3]]);
        assert!(c.check().unwrap_err().to_string().contains("not increasing"));
        let c = translations(Interpolation::Linear, &[], &[]);
        assert!(c.check().is_err());
        assert_eq!(c.sample_translation(0.0), None);
    }

    fn one_node_scene(channels: Vec<AnimationChannel>) -> Scene {
        let mut scene = Scene { nodes: vec![Node::default()], roots: vec![0], ..Default::default() };
        scene.animations.push(Animation::new("move".into(), channels));
        scene
    }

    #[test]
    fn animate_loops_over_the_duration() {
        let c = translations(Interpolation::Linear, &[0.0, 2.0], &[[0.0; 3], [4.0, 0.0, 0.0]]);
        let mut scene = one_node_scene(vec![c]);
        assert_eq!(scene.animations[0].duration, 2.0);
        for x in [0.0, 0.3, 1.0, 1.75] {
            scene.animate(0, x);
            let a = scene.nodes[0].local.translation;
            scene.animate(0, 2.0 + x);
            let b = scene.nodes[0].local.translation;
            scene.animate(0, 3.0 * 2.0 + x);
            let c = scene.nodes[0].local.translation;
            assert!(close(a, b) && close(a, c), "x = {x}: {a} {b} {c}");
            assert!(close(a, Vec3::new(2.0 * x, 0.0, 0.0)));
        }
        // Negative times wrap too; unknown animations are ignored.
        scene.animate(0, -0.5);
        assert!(close(scene.nodes[0].local.translation, Vec3::new(3.0, 0.0, 0.0)));
        scene.animate(7, 1.0);
        assert!(close(scene.nodes[0].local.translation, Vec3::new(3.0, 0.0, 0.0)));
    }

    #[test]
    fn zero_duration_animation_shows_time_zero() {
        let c = translations(Interpolation::Linear, &[0.0], &[[1.0, 2.0, 3.0]]);
        let mut scene = one_node_scene(vec![c]);
        assert_eq!(scene.animations[0].duration, 0.0);
        scene.animate(0, 5.0);
        assert_eq!(scene.nodes[0].local.translation, glam::DVec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn lights_on_nodes_follow_the_animation() {
        let down = Quat::from_rotation_x(-90f32.to_radians());
        let c = channel(
            Interpolation::Linear,
            &[0.0, 1.0, 2.0],
            Channel::Rotation(vec![Quat::IDENTITY, down, down]),
        );
        let mut scene = one_node_scene(vec![c]);
        scene.nodes[0].local.translation = glam::DVec3::new(0.0, 3.0, 0.0);
        scene.lights.push(crate::scene::Light {
            name: "spot".into(),
            kind: crate::scene::LightKind::Spot { inner_cone: 0.1, outer_cone: 0.2 },
            color: Vec3::ONE,
            intensity: 1.0,
            position: glam::DVec3::ZERO,
            direction: Vec3::NEG_Z,
            range: None,
            casts_shadows: true,
            node: Some(0),
        });
        scene.animate(0, 1.5);
        let l = &scene.lights[0];
        assert!(close(l.position, Vec3::new(0.0, 3.0, 0.0)), "{}", l.position);
        assert!(close(l.direction, Vec3::NEG_Y), "{}", l.direction);
    }

    fn shared(relative: &str) -> PathBuf {
        let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/assets/")).join(relative);
        assert!(path.exists(), "missing test asset {}", path.display());
        path
    }

    fn worlds(scene: &Scene) -> Vec<glam::DMat4> {
        scene.instances.iter().map(|i| i.world).collect()
    }

    #[test]
    fn interpolation_test_asset_loads_every_interpolation() {
        let mut scene = Scene::load(&shared("gltf/InterpolationTest/glTF/InterpolationTest.gltf")).unwrap();
        assert_eq!(scene.animations.len(), 9);
        for (i, a) in scene.animations.iter().enumerate() {
            assert!(a.duration > 0.0 && a.duration < 60.0, "animation {i} '{}': {}", a.name, a.duration);
            assert_eq!(a.channels.len(), 1);
            a.channels[0].check().unwrap();
        }
        let find = |name: &str| find_animation(&scene, name).unwrap();
        let interpolation = |name: &str| scene.animations[find(name)].channels[0].interpolation;
        assert_eq!(interpolation("Step Scale"), Interpolation::Step);
        assert_eq!(interpolation("Linear Rotation"), Interpolation::Linear);
        assert_eq!(interpolation("CubicSpline Translation"), Interpolation::CubicSpline);
        assert!(matches!(
            scene.animations[find("CubicSpline Rotation")].channels[0].values,
            Channel::Rotation(_)
        ));
        for i in 0..scene.animations.len() {
            let node = scene.animations[i].channels[0].node;
            assert!(scene.nodes[node].mesh.is_some(), "animation {i} targets a mesh node");
            scene.animate(i, 0.0);
            let before = worlds(&scene);
            let moved = [0.2, 0.4, 0.6, 0.8].iter().any(|f| {
                scene.animate(i, scene.animations[i].duration * f);
                worlds(&scene) != before
            });
            assert!(moved, "animation {i} '{}' moves nothing", scene.animations[i].name);
        }
    }

    #[test]
    fn box_animated_moves_its_instances() {
        let mut scene = Scene::load(&shared("gltf/BoxAnimated/glTF/BoxAnimated.gltf")).unwrap();
        assert_eq!(scene.animations.len(), 1);
        let a = &scene.animations[0];
        assert_eq!(a.channels.len(), 2);
        assert!(a.duration > 1.0 && a.duration < 10.0, "{}", a.duration);
        let i = find_animation(&scene, "0").unwrap();
        scene.animate(i, 0.0);
        let (before, bounds) = (worlds(&scene), scene.bounds);
        scene.animate(i, 1.3);
        assert_ne!(before, worlds(&scene));
        assert_ne!(bounds, scene.bounds, "bounds follow the instances");
        // One full loop later: the same pose.
        let posed = worlds(&scene);
        scene.animate(i, 1.3 + scene.animations[i].duration);
        for (a, b) in posed.iter().zip(worlds(&scene)) {
            assert!(a.abs_diff_eq(b, 1e-4), "{a} vs {b}");
        }
    }

    #[test]
    fn animated_cube_rotates() {
        let mut scene = Scene::load(&shared("gltf/AnimatedCube/glTF/AnimatedCube.gltf")).unwrap();
        assert_eq!(scene.animations.len(), 1);
        let a = &scene.animations[0];
        assert_eq!(a.name, "animation_AnimatedCube");
        assert!(a.duration > 0.5 && a.duration < 10.0, "{}", a.duration);
        assert!(matches!(a.channels[0].values, Channel::Rotation(_)));
        let i = find_animation(&scene, "animation_AnimatedCube").unwrap();
        scene.animate(i, 0.0);
        let before = worlds(&scene);
        scene.animate(i, scene.animations[i].duration * 0.3);
        assert_ne!(before, worlds(&scene));
    }

    #[test]
    fn find_animation_by_index_and_name() {
        let scene = Scene::load(&shared("gltf/InterpolationTest/glTF/InterpolationTest.gltf")).unwrap();
        assert_eq!(find_animation(&scene, "0").unwrap(), 0);
        assert_eq!(find_animation(&scene, "8").unwrap(), 8);
        let linear = find_animation(&scene, "Linear Translation").unwrap();
        assert_eq!(scene.animations[linear].name, "Linear Translation");
        let err = find_animation(&scene, "Bounce").unwrap_err().to_string();
        assert!(
            err.contains("Bounce") && err.contains("Step Scale") && err.contains("Linear Translation"),
            "{err}"
        );
        assert!(err.contains("InterpolationTest.gltf"), "{err}");
        let err = find_animation(&scene, "9").unwrap_err().to_string();
        assert!(err.contains("'9'"), "{err}");
        let empty = Scene::default();
        let err = find_animation(&empty, "0").unwrap_err().to_string();
        assert!(err.contains("no animations"), "{err}");
    }
}
