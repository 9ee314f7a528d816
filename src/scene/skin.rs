//! Skinning data (glTF skins, JOINTS_0 / WEIGHTS_0) and the CPU reference of linear blend skinning.
//! The GPU skins (glsl/anim/skinning.comp); the CPU poses the first frame before any GPU work exists
//! and bakes poses as static geometry so tests can compare the two.

use anyhow::{ensure, Result};
use glam::{DMat4, Mat3, Mat4, Vec3, Vec4};

use super::{Mesh, Scene, Vertex};

/// A glTF skin: the nodes that act as joints and their inverse bind matrices.
#[derive(Clone, Debug, Default)]
pub struct Skin {
    pub name: String,
    /// Node indices, in JOINTS_0 numbering.
    pub joints: Vec<usize>,
    /// One per joint (identity when the file gives none).
    pub inverse_bind: Vec<Mat4>,
}

/// Up to four joint influences per vertex. Weights sum to 1 (renormalized
/// on import).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SkinWeights {
    pub joints: Vec<[u32; 4]>,
    pub weights: Vec<[f32; 4]>,
}

impl SkinWeights {
    /// Weights must be finite and non-negative with a positive sum; zero-weight joints are set to 0 so an
    /// unused slot can never index out of range.
    pub fn new(joints: Vec<[u32; 4]>, mut weights: Vec<[f32; 4]>) -> Result<SkinWeights> {
        ensure!(
            joints.len() == weights.len(),
            "JOINTS_0 has {} elements but WEIGHTS_0 has {}",
            joints.len(),
            weights.len()
        );
        let mut joints = joints;
        let mut renormalized = 0usize;
        for (v, (j, w)) in joints.iter_mut().zip(&mut weights).enumerate() {
            ensure!(
                w.iter().all(|x| x.is_finite() && *x >= 0.0),
                "WEIGHTS_0 of vertex {v} is {w:?}: weights must be finite and non-negative"
            );
            let sum: f32 = w.iter().sum();
            ensure!(sum > 0.0, "WEIGHTS_0 of vertex {v} is all zero: the vertex belongs to no joint");
            if (sum - 1.0).abs() > 1e-3 {
                renormalized += 1;
            }
            for k in 0..4 {
                w[k] /= sum;
                if w[k] == 0.0 {
                    j[k] = 0;
                }
            }
        }
        if renormalized > 0 {
            log::warn!("{renormalized} vertices had skin weights not summing to 1; renormalized");
        }
        Ok(SkinWeights { joints, weights })
    }

    /// The largest joint index a non-zero weight uses.
    pub fn max_joint(&self) -> Option<u32> {
        self.joints.iter().flat_map(|j| j.iter().copied()).max()
    }
}

impl Scene {
    /// Joint matrices in `mesh_node`'s space: `inverse(world(mesh_node)) * world(joint) * inverse_bind`,
    /// so skinned vertices stay in mesh space near the origin and the instance keeps its world matrix.
    /// `world` is [`Scene::world_matrices`]; the product is taken in f64 (far from the origin the two
    /// world matrices cancel), then narrowed to f32.
    pub fn joint_matrices(&self, skin: usize, mesh_node: usize, world: &[DMat4]) -> Vec<Mat4> {
        let skin = &self.skins[skin];
        let to_mesh = safe_inverse(&world[mesh_node]);
        skin.joints
            .iter()
            .zip(&skin.inverse_bind)
            .map(|(&j, ib)| (to_mesh * world[j] * ib.as_dmat4()).as_mat4())
            .collect()
    }

    /// The current pose of a skinned instance (CPU skinning), or None for a
    /// rigid one.
    pub fn skinned_pose(&self, inst: &super::Instance, world: &[DMat4]) -> Option<Vec<Vertex>> {
        inst.skinned?;
        let p = &self.meshes[inst.mesh].primitives[inst.primitive];
        let joints = self.joint_matrices(self.nodes[inst.node].skin?, inst.node, world);
        Some(skin_vertices(&p.vertices, p.skin.as_ref()?, &joints))
    }

    /// A copy of the scene whose skinned instances are replaced by static
    /// meshes holding their current pose (CPU skinning): the reference for
    /// the GPU skinning path, and a way to freeze a frame.
    pub fn bake_skinning(&self) -> Scene {
        let mut out = self.clone();
        let world = self.world_matrices();
        for (n, node) in self.nodes.iter().enumerate() {
            let (Some(skin), Some(mesh)) = (node.skin, node.mesh) else { continue };
            let joints = self.joint_matrices(skin, n, &world);
            let src = &self.meshes[mesh];
            let baked = Mesh {
                name: format!("{} (baked)", src.name),
                primitives: src
                    .primitives
                    .iter()
                    .map(|p| {
                        let mut p = p.clone();
                        if let Some(w) = p.skin.take() {
                            p.vertices = skin_vertices(&p.vertices, &w, &joints);
                            p.bounds = super::tangents::bounds_of(&p.vertices);
                        }
                        p
                    })
                    .collect(),
            };
            out.nodes[n].mesh = Some(out.meshes.len());
            out.nodes[n].skin = None;
            out.meshes.push(baked);
        }
        out.update_world();
        out
    }
}

/// Inverse of an affine matrix, or identity for a singular one.
pub fn safe_inverse(m: &DMat4) -> DMat4 {
    let det = m.determinant();
    // The f32 threshold: a matrix singular in the f32 data stays singular.
    if det.is_finite() && det.abs() > f64::from(f32::MIN_POSITIVE) {
        m.inverse()
    } else {
        DMat4::IDENTITY
    }
}

/// Linear blend skinning of one vertex set, the same arithmetic as
/// glsl/anim/skinning.comp: position by the blended matrix, normal by its inverse
/// transpose, tangent by the matrix; both renormalized.
pub fn skin_vertices(vertices: &[Vertex], skin: &SkinWeights, joints: &[Mat4]) -> Vec<Vertex> {
    vertices
        .iter()
        .zip(skin.joints.iter().zip(&skin.weights))
        .map(|(v, (j, w))| {
            let mut m = Mat4::ZERO;
            for k in 0..4 {
                if w[k] > 0.0 {
                    m += joints[j[k] as usize] * w[k];
                }
            }
            let m3 = Mat3::from_mat4(m);
            let det = m3.determinant();
            let nm = if det.abs() > f32::MIN_POSITIVE { m3.inverse().transpose() } else { m3 };
            let n = (nm * Vec3::from(v.normal)).normalize_or(Vec3::from(v.normal));
            let t = Vec4::from(v.tangent);
            let tt = (m3 * t.truncate()).normalize_or(t.truncate());
            Vertex {
                position: m.transform_point3(Vec3::from(v.position)).to_array(),
                normal: n.to_array(),
                uv: v.uv,
                tangent: [tt.x, tt.y, tt.z, t.w],
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_are_renormalized_and_unused_joints_cleared() {
        let w = SkinWeights::new(vec![[3, 7, 9, 2]], vec![[0.5, 0.5, 0.0, 1.0]]).unwrap();
        assert_eq!(w.weights[0], [0.25, 0.25, 0.0, 0.5]);
        assert_eq!(w.joints[0], [3, 7, 0, 2], "a zero-weight slot must not keep joint 9");
        assert_eq!(w.max_joint(), Some(7));
    }

    #[test]
    fn bad_weights_are_rejected() {
        let zero = SkinWeights::new(vec![[0; 4]], vec![[0.0; 4]]).unwrap_err().to_string();
        assert!(zero.contains("vertex 0") && zero.contains("all zero"), "{zero}");
        let neg = SkinWeights::new(vec![[0; 4]], vec![[1.0, -0.5, 0.0, 0.0]]).unwrap_err().to_string();
        assert!(neg.contains("non-negative"), "{neg}");
        let nan = SkinWeights::new(vec![[0; 4]], vec![[f32::NAN, 0.0, 0.0, 0.0]]);
        assert!(nan.is_err());
        assert!(SkinWeights::new(vec![[0; 4]; 2], vec![[1.0, 0.0, 0.0, 0.0]]).is_err());
    }

    #[test]
    fn blend_of_two_joints_is_the_weighted_mean() {
        let v = Vertex {
            position: [1.0, 0.0, 0.0],
            normal: [0.0, 1.0, 0.0],
            tangent: [1.0, 0.0, 0.0, 1.0],
            ..Default::default()
        };
        let joints = [Mat4::IDENTITY, Mat4::from_translation(Vec3::new(0.0, 2.0, 0.0))];
        let w = SkinWeights::new(vec![[0, 1, 0, 0]], vec![[0.75, 0.25, 0.0, 0.0]]).unwrap();
        let out = skin_vertices(&[v], &w, &joints);
        assert_eq!(out[0].position, [1.0, 0.5, 0.0]);
        assert_eq!(out[0].normal, [0.0, 1.0, 0.0]);
        // A rotation by 90 degrees about Z turns the frame with it.
        let rot = [Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2)];
        let w = SkinWeights::new(vec![[0; 4]], vec![[1.0, 0.0, 0.0, 0.0]]).unwrap();
        let out = skin_vertices(&[v], &w, &rot);
        assert!(Vec3::from(out[0].position).abs_diff_eq(Vec3::Y, 1e-6));
        assert!(Vec3::from(out[0].normal).abs_diff_eq(-Vec3::X, 1e-6));
        assert!(Vec3::from_slice(&out[0].tangent[..3]).abs_diff_eq(Vec3::Y, 1e-6));
    }
}
