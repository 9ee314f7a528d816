//! Binned-SAH BVH over axis-aligned boxes, flat 32-byte nodes for the GPU
//! (the compute tracer's static BLASes use `sbvh` + `wide` instead).
//!
//! Layout (read by glsl/trace/compute.glsl, keep both in sync):
//!
//! ```text
//! struct BvhNode {           // 32 bytes, std430/scalar compatible
//!     float min[3];          //  0: bounds
//!     uint  left_or_first;   // 12
//!     float max[3];          // 16
//!     uint  count;           // 28
//! };
//! ```
//!
//! * `count == 0`: interior; children are `left_or_first` and `left_or_first + 1` (siblings adjacent).
//!   Indices are local to one BVH; the root is node 0.
//! * `count > 0`: leaf over `prim_indices[left_or_first .. left_or_first + count]`, indices into the
//!   primitive list given to [`Bvh::build`] (triangle `i` = indices `3i..3i+2` for a BLAS, an instance
//!   for a top level). `1 <= count <= MAX_LEAF`.
//! * Children have larger indices than their parent, so one reverse sweep refits ([`Bvh::refit`]).
//! * At most [`MAX_DEPTH`] levels (root = level 1), so an ordered stack traversal never holds more
//!   than `MAX_DEPTH - 1` entries.
//! * An empty primitive list gives no nodes at all; the renderer builds no BLAS for such primitives.
//!
//! Build: top-down binned SAH ([`BINS`] bins, fewer under 8 primitives) on all axes with centroid
//! extent in one pass, best plane over all axes (about 4% lower SAH cost than the largest axis only,
//! for twice the binning); iterative, partitioned in place by the same bin function (so a chosen
//! plane never leaves a side empty). Nodes over [`MAX_LEAF`] always split; smaller ones become leaves
//! when SAH says a leaf is no dearer. Coincident centroids and subtrees that would exceed
//! [`MAX_DEPTH`] fall back to an object median split on the largest centroid axis.
//!
//! Modules: `build` (binned SAH), `sbvh` (split BVH for static triangles, and the full-sweep SAH
//! builder; leaves may share a triangle), `refit` (refit, bottom-up level order), `quality` (SAH cost,
//! depth, validation), `wide` (4-wide quantized collapse).

mod build;
mod quality;
mod refit;
mod sbvh;
#[cfg(test)]
mod sbvh_tests;
#[cfg(test)]
mod test_rng;
#[cfg(test)]
mod tests;
mod wide;
#[cfg(test)]
mod wide_tests;

pub use sbvh::{SbvhStats, DEFAULT_ALPHA};
pub use wide::{WideBvh, WideNode};

use glam::Vec3;

use crate::scene::{Aabb, Scene, Vertex};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub count: u32,
}
const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);
const _: () = assert!(std::mem::align_of::<BvhNode>() == 4);

/// SAH cost of visiting one interior node (box tests of its two children).
pub const TRAVERSAL_COST: f32 = 1.0;
/// SAH cost of one primitive intersection test.
pub const INTERSECTION_COST: f32 = 1.0;
/// Bins per axis of the binned SAH.
pub const BINS: usize = 16;
/// Largest number of primitives in one leaf.
pub const MAX_LEAF: usize = 4;
/// Deepest level the builder produces (root = 1). A traversal stack of
/// `MAX_DEPTH - 1` entries (the GLSL uses 32) is therefore never exceeded.
pub const MAX_DEPTH: usize = 32;

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub prim_indices: Vec<u32>,
}

/// Largest static tree (triangles) built as a split BVH; larger ones use the binned builder.
///
/// Measured on the 2-core VM (bench/results/scale.md): on flattened Sponza (278 k triangles) spatial
/// splits cut the SAH cost 77.6 -> 65.1 and raise shadow rays 1.06 -> 1.82 Mrays/s, for a 3.4 s build
/// against 0.14 s; on the 4 M triangle terrain (small, evenly sized triangles) they buy 0.4 % SAH for
/// a build of 23 s against about 1.9 s. The line bounds the split BVH's build (0.08-0.17 Mtri/s) to
/// about 3 s here (a 1 M triangle terrain took 6.4 s under a line at 2^20, the 2 M one 0.9 s above
/// it); the disk cache (`flat_cache`) spares the second load either way.
pub const SBVH_MAX_TRIANGLES: usize = 1 << 19;

/// The builder of a static (built once, never refit) tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StaticBuilder {
    /// Split BVH ([`DEFAULT_ALPHA`]): the best trees, slow to build.
    Sbvh,
    /// Binned SAH on every core: several Mtri/s.
    Binned,
}

impl StaticBuilder {
    pub fn for_triangles(n: usize) -> StaticBuilder {
        if n <= SBVH_MAX_TRIANGLES {
            StaticBuilder::Sbvh
        } else {
            StaticBuilder::Binned
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            StaticBuilder::Sbvh => "split BVH",
            StaticBuilder::Binned => "binned SAH",
        }
    }
}

impl Bvh {
    /// A static tree over `tris` by the builder their count calls for.
    pub fn build_static(tris: &[[Vec3; 3]]) -> (Bvh, StaticBuilder) {
        let builder = StaticBuilder::for_triangles(tris.len());
        let bvh = match builder {
            StaticBuilder::Sbvh => Bvh::build_sbvh(tris, Some(DEFAULT_ALPHA)),
            StaticBuilder::Binned => Bvh::build_triangles(tris),
        };
        (bvh, builder)
    }
}

/// One object-space box per triangle (`indices.len() / 3` boxes).
pub fn triangle_aabbs(vertices: &[Vertex], indices: &[u32]) -> Vec<Aabb> {
    indices
        .chunks_exact(3)
        .map(|t| {
            let p0 = Vec3::from(vertices[t[0] as usize].position);
            let p1 = Vec3::from(vertices[t[1] as usize].position);
            let p2 = Vec3::from(vertices[t[2] as usize].position);
            Aabb { min: p0.min(p1).min(p2), max: p0.max(p1).max(p2) }
        })
        .collect()
}

/// World-space boxes of `scene.instances`, in order (`Aabb::EMPTY` for empty primitives). A top level
/// is `Bvh::build(&instance_aabbs(scene))`; its leaves then hold instance indices.
pub fn instance_aabbs(scene: &Scene) -> Vec<Aabb> {
    scene
        .instances
        .iter()
        .map(|i| scene.meshes[i.mesh].primitives[i.primitive].bounds.transformed_f64(&i.world))
        .collect()
}
