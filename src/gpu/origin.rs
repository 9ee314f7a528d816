//! The render origin: far from the world origin an f32 world cannot place
//! its geometry (the float spacing at 1e6 is 0.0625), and the GPU's
//! world-space products (instance x vertex, view x world) cancel
//! catastrophically. So everything the GPU sees — instance transforms,
//! lights, the camera, the acceleration structures' instance transforms —
//! is expressed relative to one origin near the scene, subtracted in f64 on
//! the host. Object-space vertices are untouched; a scene near the world
//! origin keeps world coordinates exactly (bit-identical images).

use glam::{DVec3, Mat4, Vec3};

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
            let w = scene.meshes[inst.mesh].primitives[inst.primitive].bounds.transformed(&inst.world);
            if w.min.is_finite() && w.max.is_finite() && !w.is_empty() {
                b = b.union(&w);
            }
        }
        let centre = if !b.is_empty() {
            (b.min.as_dvec3() + b.max.as_dvec3()) * 0.5
        } else {
            scene.cameras.first().map(|c| c.position().as_dvec3()).unwrap_or(DVec3::ZERO)
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

    /// An affine world matrix relative to the origin (its translation
    /// moved in f64; rotation and scale unchanged).
    pub fn matrix(&self, m: &Mat4) -> Mat4 {
        if self.is_zero() {
            return *m;
        }
        let mut r = *m;
        let t = m.w_axis.truncate().as_dvec3() - self.0;
        r.w_axis = t.as_vec3().extend(m.w_axis.w);
        r
    }

    /// A world point relative to the origin.
    pub fn point(&self, p: Vec3) -> Vec3 {
        if self.is_zero() {
            return p;
        }
        (p.as_dvec3() - self.0).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    #[test]
    fn moves_translations_exactly_and_keeps_the_rest() {
        let o = RenderOrigin(DVec3::new(1e6, -2e5, 3e6));
        let m = Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            Quat::from_rotation_y(0.3),
            Vec3::new(1_000_002.5, -199_999.25, 3_000_000.5),
        );
        let r = o.matrix(&m);
        assert_eq!(r.w_axis.truncate(), Vec3::new(2.5, 0.75, 0.5));
        assert_eq!(r.x_axis, m.x_axis);
        assert_eq!(o.point(Vec3::new(1_000_001.0, -200_000.0, 3e6)), Vec3::new(1.0, 0.0, 0.0));
        let zero = RenderOrigin::default();
        assert_eq!(zero.matrix(&m), m);
        assert_eq!(zero.point(Vec3::ONE), Vec3::ONE);
    }
}
