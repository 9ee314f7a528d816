//! Orbits: `orbit = { ... }` objects hung under a pivot node that the one
//! scene animation, [`SCENE_ANIMATION`], turns at constant angular speed.

use anyhow::{ensure, Context, Result};
use glam::{DVec3, Quat, Vec3};

use super::builder::Builder;
use super::checks::{finite3_f64, unit};
use super::schema::OrbitDef;
use crate::scene::animation::{Animation, AnimationChannel, Channel, Interpolation};
use crate::scene::{Node, Transform};

/// Name of the animation that holds every scene-file orbit. It has no `/`,
/// so it never clashes with a merged glTF animation (named "object/name").
pub const SCENE_ANIMATION: &str = "scene";

/// Orbit keys per turn: 45 degrees apart, so the shortest-path slerp between
/// neighbours is unambiguous, and about a fixed axis it is exact (constant
/// angular speed, the true circle), not an approximation.
const ORBIT_KEYS_PER_TURN: usize = 8;

/// Guards against a tiny period making millions of keys.
const MAX_ORBIT_TURNS: f32 = 1000.0;

/// A validated `orbit`, before its pivot exists.
pub(super) struct OrbitSpec {
    pub(super) center: DVec3,
    pub(super) axis: Vec3,
    pub(super) period: f32,
}

/// An orbit whose pivot node is in the scene; it becomes one channel of the
/// scene animation once every object (and so the longest period) is known.
pub(super) struct Orbit {
    pub(super) pivot: usize,
    pub(super) axis: Vec3,
    pub(super) period: f32,
    /// "file:line: object 'name'", for errors found after all objects.
    pub(super) context: String,
}

impl Builder<'_> {
    /// One animation, [`SCENE_ANIMATION`], with a rotation channel per orbit pivot, looping at the longest
    /// period. Every other period must divide it so each orbit closes seamlessly at the loop (animations
    /// loop whole, not per channel).
    pub(super) fn add_orbit_animation(&mut self) -> Result<()> {
        let Some(duration) = self.orbits.iter().map(|o| o.period).reduce(f32::max) else { return Ok(()) };
        let mut channels = Vec::with_capacity(self.orbits.len());
        for o in &self.orbits {
            let ratio = duration / o.period;
            let turns = ratio.round();
            ensure!(
                turns <= MAX_ORBIT_TURNS,
                "{}: orbit.period {} s makes {turns} turns in the longest orbit period ({duration} s); \
                 at most {MAX_ORBIT_TURNS} are allowed",
                o.context,
                o.period
            );
            ensure!(
                (ratio - turns).abs() <= 1e-3 * turns,
                "{}: orbit.period {} s does not divide the longest orbit period {duration} s: all orbits \
                 share the '{SCENE_ANIMATION}' animation, which loops every {duration} s, so each must make \
                 a whole number of turns in it",
                o.context,
                o.period
            );
            channels.push(orbit_channel(o.pivot, o.axis, turns as usize, duration));
        }
        self.scene.animations.push(Animation::new(SCENE_ANIMATION.into(), channels));
        Ok(())
    }

    /// Hangs root node `node` under a new pivot at `center` that the orbit turns; the node's transform
    /// becomes pivot-relative, so at t = 0 the object stays where its `translation` put it.
    pub(super) fn add_pivot(&mut self, node: usize, center: DVec3, name: &str) -> usize {
        let pivot = self.scene.nodes.len();
        self.scene.nodes.push(Node {
            name: format!("{name} (orbit pivot)"),
            local: Transform { translation: center, ..Default::default() },
            children: vec![node],
            ..Default::default()
        });
        let child = &mut self.scene.nodes[node];
        child.parent = Some(pivot);
        child.local.translation -= center;
        // The pivot takes the object's place among the roots.
        for r in self.scene.roots.iter_mut().filter(|r| **r == node) {
            *r = pivot;
        }
        pivot
    }
}

pub(super) fn orbit_from_def(o: &OrbitDef) -> Result<OrbitSpec> {
    let center = finite3_f64(o.center.context("orbit needs `center`")?, "orbit.center")?;
    let axis = unit(o.axis.unwrap_or([0.0, 1.0, 0.0]), "orbit.axis")?;
    let period = o.period.context("orbit needs `period` (seconds per turn)")?;
    ensure!(period > 0.0 && period.is_finite(), "orbit.period must be positive and finite (got {period})");
    Ok(OrbitSpec { center, axis, period })
}

/// LINEAR rotation keys for `turns` full turns about `axis` over `duration`
/// seconds, at constant angular speed; the last key (at `duration`) equals
/// the first, so the loop is seamless.
fn orbit_channel(node: usize, axis: Vec3, turns: usize, duration: f32) -> AnimationChannel {
    let n = ORBIT_KEYS_PER_TURN * turns;
    let times = (0..=n).map(|k| duration * k as f32 / n as f32).collect();
    // The angle within the turn, so rounding does not grow with the turn count.
    let step = std::f32::consts::TAU / ORBIT_KEYS_PER_TURN as f32;
    let rotations =
        (0..=n).map(|k| Quat::from_axis_angle(axis, step * (k % ORBIT_KEYS_PER_TURN) as f32)).collect();
    AnimationChannel {
        node,
        times,
        interpolation: Interpolation::Linear,
        values: Channel::Rotation(rotations),
    }
}
