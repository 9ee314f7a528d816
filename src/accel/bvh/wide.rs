//! 4-wide BVH with 8-bit quantized child bounds, collapsed from a binary
//! [`Bvh`]: the compute tracer's static BLASes (glsl/trace/compute_wide.glsl).
//!
//! Layout (64 bytes, one cache line; keep in sync with any GLSL reader):
//!
//! ```text
//! struct WideNode {              // 64 bytes, std430/scalar compatible
//!     float origin[3];           //  0: quantization origin (node min)
//!     uint  meta;                // 12: exp x | exp y << 8 | exp z << 16 | children << 24
//!     uint  qmin[3];             // 16: per axis, child i's byte at bits 8i..8i+7
//!     uint  qmax[3];             // 28
//!     uint  child[4];            // 40: see below
//!     uint  pad[2];              // 56
//! };
//! ```
//!
//! * Child `i < children` has box `origin + q * 2^(exp - 127)` per axis, `q` its `qmin` / `qmax` byte.
//!   `q * 2^e` is exact, so decoding rounds once with or without FMA, and the builder checks every
//!   decoded box contains the exact child box.
//! * `child[i]` with bit 30 clear: a wide node index. Set: a leaf over
//!   `prim_indices[first .. first + count]`, `first = child & 0x07FF_FFFF`,
//!   `count = (child >> 27) & 7` (1..=4).
//! * Node 0 is the root; children come after their parents.
//!
//! Why, for a CPU device (llvmpipe runs each invocation as a SIMD lane): one 64-byte fetch instead of
//! two 32-byte nodes per binary level, half the levels and stack traffic, and at most 4 hit children to
//! sort. 8-bit quantization fits 4 children plus origin in one cache line (16-bit needs 80+ bytes);
//! 8-wide (CWBVH) halves levels again but costs 8 box tests and a longer sort per lane.

use super::{Bvh, MAX_LEAF};
use crate::scene::Aabb;
use glam::Vec3;

/// Children per wide node.
pub const WIDTH: usize = 4;
/// Binary trees of at least this many nodes collapse on every core.
const PAR_MIN_NODES: usize = 1 << 16;
/// Subtrees the top of a large tree is opened into before they collapse in parallel (fixed: the
/// tree does not depend on the machine).
const PAR_SUBTREES: usize = 32;
pub const LEAF_BIT: u32 = crate::gpu::shared::BVH_WIDE_LEAF;
const _: () = assert!(LEAF_BIT == 1 << 30);
const FIRST_MASK: u32 = 0x07FF_FFFF;
const COUNT_SHIFT: u32 = 27;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WideNode {
    pub origin: [f32; 3],
    pub meta: u32,
    pub qmin: [u32; 3],
    pub qmax: [u32; 3],
    pub child: [u32; WIDTH],
    pub pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<WideNode>() == 64);
const _: () = assert!(MAX_LEAF <= 7);

#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    pub nodes: Vec<WideNode>,
    /// Same as the source tree's (leaves keep their primitive ranges).
    pub prim_indices: Vec<u32>,
    /// Per wide node and child slot: the binary node it was collapsed from
    /// (for checks of the quantization against the exact boxes).
    pub source: Vec<[u32; WIDTH]>,
}

impl WideNode {
    pub fn children(&self) -> usize {
        (self.meta >> 24) as usize
    }

    fn scale(&self, axis: usize) -> f32 {
        exp2i(((self.meta >> (8 * axis)) & 0xFF) as i32 - 127)
    }

    /// Decoded (conservative) box of child `i`.
    pub fn child_bounds(&self, i: usize) -> Aabb {
        let (mut min, mut max) = (Vec3::ZERO, Vec3::ZERO);
        for k in 0..3 {
            let s = self.scale(k);
            min[k] = self.origin[k] + ((self.qmin[k] >> (8 * i)) & 0xFF) as f32 * s;
            max[k] = self.origin[k] + ((self.qmax[k] >> (8 * i)) & 0xFF) as f32 * s;
        }
        Aabb { min, max }
    }

    /// `Some((first, count))` for a leaf child.
    pub fn leaf(&self, i: usize) -> Option<(usize, usize)> {
        let c = self.child[i];
        (c & LEAF_BIT != 0).then_some(((c & FIRST_MASK) as usize, ((c >> COUNT_SHIFT) & 7) as usize))
    }
}

/// 2^e for e in -126..=127 (normal floats), built from the bits.
pub(super) fn exp2i(e: i32) -> f32 {
    f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
}

/// ceil(log2(x)) for a positive finite x (from its bits; subnormals count as 2^-126).
pub(super) fn ceil_log2(x: f32) -> i32 {
    let bits = x.to_bits();
    let exp = (bits >> 23) as i32 - 127;
    if exp < -126 {
        -126
    } else if bits & 0x7F_FFFF != 0 {
        exp + 1
    } else {
        exp
    }
}

fn node_bounds(b: &Bvh, i: usize) -> Aabb {
    Aabb { min: b.nodes[i].min.into(), max: b.nodes[i].max.into() }
}

/// Quantizes `boxes` relative to their union: the smallest exponent per axis
/// whose decoded boxes all contain the exact ones.
fn quantize(boxes: &[Aabb]) -> WideNode {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for b in boxes {
        lo = lo.min(b.min);
        hi = hi.max(b.max);
    }
    let mut n = WideNode { origin: lo.to_array(), meta: (boxes.len() as u32) << 24, ..Default::default() };
    for k in 0..3 {
        let ext = hi[k] - lo[k];
        // Smallest power of two with 255 * 2^e >= ext (from the bits of ext / 255, which the check
        // below corrects if its rounding was short), then up while float rounding of the decode would
        // cut into a box. Floor and ceil by conversion: the values are >= 0, and at the crate's
        // opt-level the library calls were a third of the collapse.
        let mut e = if ext > 0.0 { ceil_log2(ext / 255.0) } else { -126 };
        'grow: loop {
            // 1 / s is exact (a power of two), so multiplying is dividing, without the divide.
            let (s, inv) = (exp2i(e), 1.0 / exp2i(e));
            let (mut qlo, mut qhi) = (0u32, 0u32);
            for (i, b) in boxes.iter().enumerate() {
                let mut a = (((b.min[k] - lo[k]) * inv) as u32).min(255);
                while a > 0 && lo[k] + a as f32 * s > b.min[k] {
                    a -= 1;
                }
                let x = (b.max[k] - lo[k]) * inv;
                let mut z = x as u32;
                z = if (z as f32) < x { z + 1 } else { z }.min(255);
                while z < 255 && lo[k] + (z as f32) * s < b.max[k] {
                    z += 1;
                }
                if lo[k] + a as f32 * s > b.min[k] || lo[k] + z as f32 * s < b.max[k] {
                    if e >= 127 {
                        break;
                    }
                    e += 1;
                    continue 'grow;
                }
                qlo |= a << (8 * i);
                qhi |= z << (8 * i);
            }
            n.qmin[k] = qlo;
            n.qmax[k] = qhi;
            n.meta |= ((e.clamp(-126, 127) + 127) as u32) << (8 * k);
            break;
        }
    }
    n
}

impl WideBvh {
    /// Each wide node takes up to [`WIDTH`] children by opening its largest-area interior child (SAH's
    /// most visited). Large trees collapse their top breadth first, then the subtrees below it on every
    /// core, linked in after the top (node order differs from a serial collapse, nothing else).
    pub fn from_binary(bvh: &Bvh) -> WideBvh {
        Self::from_binary_in(bvh, PAR_MIN_NODES)
    }

    /// The collapse, on every core for trees of at least `par_min` nodes.
    pub(super) fn from_binary_in(bvh: &Bvh, par_min: usize) -> WideBvh {
        let mut w = WideBvh { prim_indices: bvh.prim_indices.clone(), ..Default::default() };
        if bvh.nodes.is_empty() {
            return w;
        }
        // (wide node to fill, binary node it stands for)
        let mut todo = vec![(0usize, 0usize)];
        w.nodes.push(WideNode::default());
        w.source.push([0; WIDTH]);
        if bvh.nodes.len() < par_min {
            while let Some((wi, bi)) = todo.pop() {
                w.expand(bvh, wi, bi, &mut todo);
            }
            return w;
        }
        let mut head = 0;
        while head < todo.len() && todo.len() - head < PAR_SUBTREES {
            let (wi, bi) = todo[head];
            head += 1;
            w.expand(bvh, wi, bi, &mut todo);
        }
        let pending = &todo[head..];
        let subtrees = crate::par::map(pending.len(), &[], |k| {
            let mut sub =
                WideBvh { nodes: vec![WideNode::default()], source: vec![[0; WIDTH]], ..Default::default() };
            let mut stack = vec![(0, pending[k].1)];
            while let Some((wi, bi)) = stack.pop() {
                sub.expand(bvh, wi, bi, &mut stack);
            }
            sub
        })
        .unwrap_or_else(|e| panic!("wide BVH: {e}"));
        // Subtree node j > 0 lands at base + j - 1; its root fills the slot the top reserved.
        let mut bases = Vec::with_capacity(subtrees.len());
        let mut next = w.nodes.len() as u32;
        for sub in &subtrees {
            bases.push(next);
            next += sub.nodes.len() as u32 - 1;
        }
        let link = |k: usize, &n: &WideNode| {
            let mut n = n;
            let children = n.children();
            for c in &mut n.child[..children] {
                if *c & LEAF_BIT == 0 {
                    *c = bases[k] + *c - 1;
                }
            }
            n
        };
        for (k, (&(at, _), sub)) in pending.iter().zip(&subtrees).enumerate() {
            w.nodes[at] = link(k, &sub.nodes[0]);
            w.source[at] = sub.source[0];
        }
        let parts: Vec<&[WideNode]> = subtrees.iter().map(|s| &s.nodes[1..]).collect();
        crate::par::extend_parts(&mut w.nodes, &parts, link).unwrap_or_else(|e| panic!("wide BVH: {e}"));
        let parts: Vec<&[[u32; WIDTH]]> = subtrees.iter().map(|s| &s.source[1..]).collect();
        crate::par::extend_parts(&mut w.source, &parts, |_, &s| s)
            .unwrap_or_else(|e| panic!("wide BVH: {e}"));
        w
    }

    /// Fills wide node `wi` for binary node `bi`, appending its interior children as new nodes to fill
    /// (pushed on `todo`).
    fn expand(&mut self, bvh: &Bvh, wi: usize, bi: usize, todo: &mut Vec<(usize, usize)>) {
        // Fixed arrays, not vectors: two allocations per node were a third of the collapse.
        let (mut kids, mut n) = ([0usize; WIDTH], 2);
        if bvh.nodes[bi].count > 0 {
            (kids[0], n) = (bi, 1); // a leaf root: one leaf child
        } else {
            let f = bvh.nodes[bi].left_or_first as usize;
            kids[..2].copy_from_slice(&[f, f + 1]);
        }
        while n < WIDTH {
            let open = kids[..n]
                .iter()
                .enumerate()
                .filter(|(_, &c)| bvh.nodes[c].count == 0)
                .max_by(|a, b| area(&node_bounds(bvh, *a.1)).total_cmp(&area(&node_bounds(bvh, *b.1))));
            let Some((slot, &c)) = open else { break };
            let f = bvh.nodes[c].left_or_first as usize;
            kids[slot] = f;
            kids[n] = f + 1;
            n += 1;
        }
        let kids = &kids[..n];
        let mut boxes = [Aabb::EMPTY; WIDTH];
        for (b, &c) in boxes.iter_mut().zip(kids) {
            *b = node_bounds(bvh, c);
        }
        let mut node = quantize(&boxes[..n]);
        for (i, &c) in kids.iter().enumerate() {
            let b = &bvh.nodes[c];
            node.child[i] = if b.count > 0 {
                assert!(
                    b.left_or_first <= FIRST_MASK,
                    "wide BVH: primitive index {} overflows",
                    b.left_or_first
                );
                LEAF_BIT | (b.count << COUNT_SHIFT) | b.left_or_first
            } else {
                let next = self.nodes.len();
                self.nodes.push(WideNode::default());
                self.source.push([0; WIDTH]);
                todo.push((next, c));
                next as u32
            };
            self.source[wi][i] = c as u32;
        }
        self.nodes[wi] = node;
    }

    /// Bytes on the GPU: nodes plus primitive indices.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<WideNode>() + 4 * self.prim_indices.len()
    }
}

fn area(b: &Aabb) -> f32 {
    let d = b.max - b.min;
    2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
}
