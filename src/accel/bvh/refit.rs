//! Refitting a built tree to moved primitives, on the CPU, and the
//! level-by-level order a parallel (GPU) refit follows.

use super::build::Bounds;
use super::Bvh;
use crate::scene::Aabb;

impl Bvh {
    /// Bounds of the root (empty for an empty BVH).
    pub fn root_bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| Aabb { min: n.min.into(), max: n.max.into() })
    }

    /// Recomputes every node's bounds for moved primitives (same topology:
    /// `aabbs` must describe the same primitives as at build time). Children
    /// come after their parents, so one reverse sweep is bottom-up.
    pub fn refit(&mut self, aabbs: &[Aabb]) {
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            let first = n.left_or_first as usize;
            let mut b = Bounds::EMPTY;
            if n.count > 0 {
                for &p in &self.prim_indices[first..first + n.count as usize] {
                    b.grow(&Bounds::from_aabb(&aabbs[p as usize]));
                }
            } else {
                b = Bounds::of_node(&self.nodes[first]);
                b.grow(&Bounds::of_node(&self.nodes[first + 1]));
            }
            self.nodes[i].min = b.min;
            self.nodes[i].max = b.max;
        }
    }

    /// Node indices grouped by depth, deepest level first, plus the level
    /// boundaries into that list (`levels.len() == depth + 1`): the order a
    /// parallel refit must follow, one level at a time.
    pub fn levels(&self) -> (Vec<u32>, Vec<u32>) {
        let mut depth = vec![0usize; self.nodes.len()];
        // Children come after their parents, so one forward sweep suffices.
        for (i, n) in self.nodes.iter().enumerate() {
            if n.count == 0 {
                let c = n.left_or_first as usize;
                depth[c] = depth[i] + 1;
                depth[c + 1] = depth[i] + 1;
            }
        }
        let levels = depth.iter().max().map_or(0, |d| d + 1);
        let mut order = Vec::with_capacity(self.nodes.len());
        let mut bounds = vec![0u32];
        for d in (0..levels).rev() {
            order.extend((0..self.nodes.len() as u32).filter(|&i| depth[i as usize] == d));
            bounds.push(order.len() as u32);
        }
        (order, bounds)
    }
}
