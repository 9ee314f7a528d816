//! Which G-buffer draws a frame records, decided on the host each frame: an instance whose world bounds
//! lie entirely outside one frustum plane is not drawn (clipping would remove all its triangles, so the
//! image cannot change), and one whose transform mirrors (negative determinant) is drawn with the
//! opposite front face, so back-face culling of single-sided geometry keeps its outside.
//!
//! Bounds: a rigid instance's primitive box under its world matrix; a skinned one's is the union of
//! that box under every joint matrix of the current pose (a skinned vertex is a convex blend of its
//! joints' transforms of it, so it lies in that union).

use glam::{DMat4, DVec3, DVec4};

use crate::gpu::origin::RenderOrigin;
use crate::gpu::scene::GpuScene;
use crate::scene::{Aabb, Scene};

/// One draw of the frame: an index into `GpuScene::draws`, its winding and its instance's transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameDraw {
    pub draw: u32,
    /// The instance's transform mirrors: its front faces wind clockwise.
    pub mirrored: bool,
    /// The instance's world matrix relative to the render origin, as the instance buffer holds it: the
    /// G-buffer's vertex stage takes it as a push constant instead of fetching the instance per vertex.
    pub world: glam::Mat4,
}

/// The frame's draws after culling.
#[derive(Clone, Debug, Default)]
pub struct DrawList {
    pub draws: Vec<FrameDraw>,
    /// Draws left out as outside the view frustum.
    pub culled: u32,
}

/// The five planes (a, b, c, d: inside where a x + b y + c z + d >= 0) of
/// the reversed-Z, infinite-far frustum of `view_proj` (camera/projection):
/// left, right, bottom, top and near; the far plane is at infinity.
pub fn frustum_planes(view_proj: &DMat4) -> [DVec4; 5] {
    let r = |i: usize| view_proj.row(i);
    let (x, y, z, w) = (r(0), r(1), r(2), r(3));
    // Clip space: -w <= x, y <= w and z <= w (z = znear, w = view distance).
    [w + x, w - x, w + y, w - y, w - z]
}

/// Whether the box lies entirely on the outside of one of `planes`.
pub fn outside(planes: &[DVec4; 5], b: &Aabb) -> bool {
    if b.is_empty() {
        return true;
    }
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    planes.iter().any(|p| {
        // The box corner furthest along the plane's normal.
        let c = DVec3::new(
            if p.x >= 0.0 { hi.x } else { lo.x },
            if p.y >= 0.0 { hi.y } else { lo.y },
            if p.z >= 0.0 { hi.z } else { lo.z },
        );
        p.truncate().dot(c) + p.w < 0.0
    })
}

/// The draws of `gpu` visible through `view_proj` (relative to `origin`,
/// like every GPU transform) with the scene in its current pose.
pub fn draw_list(scene: &Scene, gpu: &GpuScene, origin: RenderOrigin, view_proj: &DMat4) -> DrawList {
    let planes = frustum_planes(view_proj);
    let worlds = scene.instances.iter().any(|i| i.skinned.is_some()).then(|| scene.world_matrices());
    let mut list = DrawList::default();
    for (k, d) in gpu.draws.iter().enumerate() {
        let Some(inst) = scene.instances.get(d.instance as usize) else { continue };
        let world = origin.relative(&inst.world);
        let bounds = &scene.meshes[inst.mesh].primitives[inst.primitive].bounds;
        let local = match (&worlds, scene.nodes[inst.node].skin, inst.skinned) {
            (Some(w), Some(skin), Some(_)) => scene
                .joint_matrices(skin, inst.node, w)
                .iter()
                .fold(Aabb::EMPTY, |acc, j| acc.union(&bounds.transformed(j))),
            _ => *bounds,
        };
        let world_box = local.transformed(&world.as_mat4());
        // Non-finite bounds (a degenerate pose) are drawn rather than guessed at.
        let finite = world_box.min.is_finite() && world_box.max.is_finite();
        if finite && outside(&planes, &world_box) {
            list.culled += 1;
            continue;
        }
        list.draws.push(FrameDraw {
            draw: k as u32,
            mirrored: world.determinant() < 0.0,
            world: world.as_mat4(),
        });
    }
    list
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;
    use glam::Vec3;

    fn camera_planes() -> [DVec4; 5] {
        // At the origin looking down -Z, 90 degrees vertical, square.
        let cam = Camera::look_at("c", Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 90f32.to_radians(), 0.1);
        frustum_planes(&(cam.projection(1.0).as_dmat4() * cam.view()))
    }

    fn cube(c: [f32; 3], h: f32) -> Aabb {
        let c = Vec3::from(c);
        Aabb { min: c - h, max: c + h }
    }

    /// Boxes in front, straddling a side plane or the near plane are kept; behind the camera, beyond a side
    /// plane or inside the near distance they are culled.
    #[test]
    fn boxes_are_culled_only_when_entirely_outside_one_plane() {
        let p = camera_planes();
        assert!(!outside(&p, &cube([0.0, 0.0, -5.0], 1.0)), "straight ahead");
        assert!(!outside(&p, &cube([5.5, 0.0, -5.0], 1.0)), "straddles the right plane (x = -z)");
        assert!(!outside(&p, &cube([0.0, 0.0, 0.0], 1.0)), "contains the camera");
        assert!(!outside(&p, &cube([0.0, 0.0, -1e6], 1.0)), "far away: the far plane is at infinity");
        assert!(outside(&p, &cube([0.0, 0.0, 5.0], 1.0)), "behind");
        assert!(outside(&p, &cube([8.0, 0.0, -5.0], 1.0)), "right of the frustum");
        assert!(outside(&p, &cube([0.0, -8.0, -5.0], 1.0)), "below the frustum");
        assert!(outside(&p, &cube([0.0, 0.0, -0.05], 0.01)), "between the camera and the near plane");
        assert!(outside(&p, &Aabb::EMPTY), "an empty box");
    }
}
