//! Inspecting a built tree: its SAH cost, its depth, and a check of every
//! layout invariant.

use super::build::Bounds;
use super::{Bvh, INTERSECTION_COST, MAX_DEPTH, MAX_LEAF, TRAVERSAL_COST};
use glam::Vec3;

use crate::scene::Aabb;

impl Bvh {
    /// SAH cost of the tree normalised by the root's surface area:
    /// `sum(interior) TRAVERSAL_COST * A(n) / A(root) + sum(leaves)
    /// INTERSECTION_COST * count * A(n) / A(root)`. 0 for an empty BVH or a
    /// root without area.
    pub fn sah_cost(&self) -> f32 {
        let Some(root) = self.nodes.first() else { return 0.0 };
        let ra = Bounds::of_node(root).area();
        if ra <= 0.0 || !ra.is_finite() {
            return 0.0;
        }
        let sum: f64 = self
            .nodes
            .iter()
            .map(|n| {
                let a = Bounds::of_node(n).area() as f64;
                let c = if n.count > 0 { INTERSECTION_COST * n.count as f32 } else { TRAVERSAL_COST };
                a * c as f64
            })
            .sum();
        (sum / ra as f64) as f32
    }

    /// Number of levels (root only = 1, empty = 0).
    pub fn depth(&self) -> usize {
        if self.nodes.is_empty() {
            return 0;
        }
        let mut max = 0;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            max = max.max(d);
            let n = self.nodes[i];
            if n.count == 0 {
                stack.push((n.left_or_first as usize, d + 1));
                stack.push((n.left_or_first as usize + 1, d + 1));
            }
        }
        max
    }

    /// Checks the layout invariants: node and primitive indices in range,
    /// children after their parents, every node reachable exactly once,
    /// every primitive in exactly one leaf, `1 <= count <= MAX_LEAF`, depth
    /// <= MAX_DEPTH, and bounds containing their children / primitives.
    pub fn validate(&self, aabbs: &[Aabb]) -> Result<(), String> {
        if self.nodes.is_empty() {
            return match (aabbs.len(), self.prim_indices.len()) {
                (0, 0) => Ok(()),
                (a, p) => Err(format!("no nodes but {a} primitives and {p} primitive indices")),
            };
        }
        if self.prim_indices.len() != aabbs.len() {
            return Err(format!(
                "{} primitive indices for {} primitives",
                self.prim_indices.len(),
                aabbs.len()
            ));
        }
        let mut visited = vec![false; self.nodes.len()];
        let mut seen = vec![0u32; aabbs.len()];
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            if std::mem::replace(&mut visited[i], true) {
                return Err(format!("node {i} reached twice"));
            }
            if depth > MAX_DEPTH {
                return Err(format!("node {i} at depth {depth} > {MAX_DEPTH}"));
            }
            let n = &self.nodes[i];
            let b = Bounds::of_node(n);
            let first = n.left_or_first as usize;
            if n.count == 0 {
                if first <= i || first + 1 >= self.nodes.len() {
                    return Err(format!("node {i}: children {first}, {} out of order or range", first + 1));
                }
                for c in [first, first + 1] {
                    if !b.contains(&Bounds::of_node(&self.nodes[c])) {
                        return Err(format!("node {i} does not contain its child {c}"));
                    }
                    stack.push((c, depth + 1));
                }
            } else {
                let end = first + n.count as usize;
                if n.count as usize > MAX_LEAF || end > self.prim_indices.len() {
                    return Err(format!("leaf {i}: primitives {first}..{end} too many or out of range"));
                }
                for &p in &self.prim_indices[first..end] {
                    let p = p as usize;
                    if p >= aabbs.len() {
                        return Err(format!("leaf {i}: primitive {p} out of range"));
                    }
                    seen[p] += 1;
                    if !b.contains(&Bounds::from_aabb(&aabbs[p])) {
                        return Err(format!("leaf {i} does not contain its primitive {p}"));
                    }
                }
            }
        }
        if let Some(i) = visited.iter().position(|v| !v) {
            return Err(format!("node {i} is unreachable"));
        }
        match seen.iter().position(|&c| c != 1) {
            Some(p) => Err(format!("primitive {p} referenced {} times", seen[p])),
            None => Ok(()),
        }
    }

    /// Checks an SBVH (leaves may share a triangle and hold clipped parts): [`Bvh::validate`]'s structure
    /// checks, every triangle referenced, and every triangle covered: a grid of points on it (vertices,
    /// edges, interior) each lies in the box of some leaf that references it.
    pub fn validate_split(&self, tris: &[[Vec3; 3]]) -> Result<(), String> {
        if self.nodes.is_empty() {
            return match (tris.len(), self.prim_indices.len()) {
                (0, 0) => Ok(()),
                (a, p) => Err(format!("no nodes but {a} triangles and {p} primitive indices")),
            };
        }
        let mut visited = vec![false; self.nodes.len()];
        let mut leaves_of: Vec<Vec<usize>> = vec![Vec::new(); tris.len()];
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            if std::mem::replace(&mut visited[i], true) {
                return Err(format!("node {i} reached twice"));
            }
            if depth > MAX_DEPTH {
                return Err(format!("node {i} at depth {depth} > {MAX_DEPTH}"));
            }
            let n = &self.nodes[i];
            let first = n.left_or_first as usize;
            if n.count == 0 {
                if first <= i || first + 1 >= self.nodes.len() {
                    return Err(format!("node {i}: children {first}, {} out of order or range", first + 1));
                }
                for c in [first, first + 1] {
                    if !Bounds::of_node(n).contains(&Bounds::of_node(&self.nodes[c])) {
                        return Err(format!("node {i} does not contain its child {c}"));
                    }
                    stack.push((c, depth + 1));
                }
            } else {
                let end = first + n.count as usize;
                if n.count as usize > MAX_LEAF || end > self.prim_indices.len() {
                    return Err(format!("leaf {i}: primitives {first}..{end} too many or out of range"));
                }
                for &p in &self.prim_indices[first..end] {
                    let list = leaves_of
                        .get_mut(p as usize)
                        .ok_or(format!("leaf {i}: triangle {p} out of range"))?;
                    list.push(i);
                }
            }
        }
        if let Some(i) = visited.iter().position(|v| !v) {
            return Err(format!("node {i} is unreachable"));
        }
        const STEPS: u32 = 8;
        for (t, (tri, leaves)) in tris.iter().zip(&leaves_of).enumerate() {
            if leaves.is_empty() {
                return Err(format!("triangle {t} is in no leaf"));
            }
            for a in 0..=STEPS {
                for b in 0..=STEPS - a {
                    let (u, v) = (a as f32 / STEPS as f32, b as f32 / STEPS as f32);
                    let p = if a == 0 && b == 0 {
                        tri[0]
                    } else if a == STEPS {
                        tri[1]
                    } else if b == STEPS {
                        tri[2]
                    } else {
                        tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v
                    };
                    // The sample point itself carries the rounding of its
                    // interpolation: a few ulps of the vertices' magnitude.
                    let mag = tri[0].abs().max(tri[1].abs()).max(tri[2].abs());
                    let inside = |l: &usize| {
                        let n = &self.nodes[*l];
                        (0..3).all(|k| {
                            let tol = 8.0 * f32::EPSILON * mag[k];
                            n.min[k] - tol <= p[k] && p[k] <= n.max[k] + tol
                        })
                    };
                    if !leaves.iter().any(inside) {
                        return Err(format!(
                            "point {p} of triangle {t} is outside all its leaves {leaves:?}"
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}
