//! The render origin: far from the world origin f32 cannot place geometry (spacing 0.0625 at 1e6) and
//! the GPU's world-space products cancel catastrophically. The scene keeps placements in f64; all the
//! GPU sees (instance transforms, lights, camera, AS instance transforms) is narrowed to f32 only after
//! subtracting this origin, in f64 on the host. Object-space vertices are untouched.

use glam::{DMat4, DVec3, Mat4, Vec3};

use crate::scene::{Aabb, Scene};

/// Scenes whose centre lies within this distance of the world origin (on
/// every axis) render in world coordinates.
pub const REBASE_BEYOND: f64 = 256.0;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderOrigin(pub DVec3);

impl RenderOrigin {
    /// The centre of the instances' world bounds (of the first camera when
    /// there are none), rounded to whole units; zero near the world origin.
    pub fn for_scene(scene: &Scene) -> RenderOrigin {
        let mut b = Aabb::EMPTY;
        for inst in &scene.instances {
            let w = scene.meshes[inst.mesh].primitives[inst.primitive].bounds.transformed_f64(&inst.world);
            if w.min.is_finite() && w.max.is_finite() && !w.is_empty() {
                b = b.union(&w);
            }
        }
        let centre = if !b.is_empty() {
            (b.min.as_dvec3() + b.max.as_dvec3()) * 0.5
        } else {
            scene.cameras.first().map(|c| c.position_f64()).unwrap_or(DVec3::ZERO)
        };
        if centre.abs().max_element() < REBASE_BEYOND || !centre.is_finite() {
            RenderOrigin(DVec3::ZERO)
        } else {
            RenderOrigin(centre.round())
        }
    }

    pub fn is_zero(&self) -> bool {
        self.0 == DVec3::ZERO
    }

    /// An affine world matrix relative to the origin, narrowed to f32
    /// (its translation moved in f64; rotation and scale unchanged).
    pub fn matrix(&self, m: &DMat4) -> Mat4 {
        self.relative(m).as_mat4()
    }

    /// [`RenderOrigin::matrix`] kept in f64 (for products still to come).
    pub fn relative(&self, m: &DMat4) -> DMat4 {
        let mut r = *m;
        r.w_axis = (m.w_axis.truncate() - self.0).extend(m.w_axis.w);
        r
    }

    /// A world point relative to the origin, narrowed to f32.
    pub fn point(&self, p: DVec3) -> Vec3 {
        (p - self.0).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn moves_translations_exactly_and_keeps_the_rest() {
        let o = RenderOrigin(DVec3::new(1e6, -2e5, 3e6));
        // Offsets an f32 world could not hold at 1e6 (spacing 0.0625).
        let m = DMat4::from_scale_rotation_translation(
            DVec3::splat(2.0),
            DQuat::from_rotation_y(0.3),
            DVec3::new(1_000_002.501, -199_999.249, 3_000_000.003),
        );
        let r = o.matrix(&m);
        let t = r.w_axis.truncate();
        assert!((t - Vec3::new(2.501, 0.751, 0.003)).abs().max_element() < 1e-6, "{t}");
        assert_eq!(r.x_axis, m.x_axis.as_vec4());
        assert_eq!(o.point(DVec3::new(1_000_001.0, -200_000.0, 3e6 + 0.004)), Vec3::new(1.0, 0.0, 0.004));
        let zero = RenderOrigin::default();
        assert_eq!(zero.matrix(&m), m.as_mat4());
        assert_eq!(zero.point(DVec3::ONE), Vec3::ONE);
    }
}
