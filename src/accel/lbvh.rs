//! A device-side BVH builder, measured against the host's binned SAH build (issue 36): an LBVH
//! (Lauterbach et al. 2009; the hierarchy by Karras 2012) in compute shaders (glsl/lbvh/). Morton
//! codes of the triangle centroids, a stable radix sort (LBVH_RADIX_BITS per pass, one invocation per
//! block of keys), every internal node's range and split from the sorted keys in parallel, then boxes
//! bottom up with one visit counter per node. One leaf per triangle.
//!
//! `bench --builders` times it per pass with timestamps and reads the tree back to measure its SAH
//! cost beside the host builders' (bench/results/builders.md). The renderer keeps the host build: see
//! there why. [`reference`] is the same algorithm on the host (the tests compare the two).

use anyhow::{ensure, Result};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;

use super::bvh::{Bvh, BvhNode};
use crate::gpu::shared::{
    LBVH_BOXES, LBVH_CHILDREN, LBVH_FLAGS, LBVH_GROUP, LBVH_HISTOGRAM, LBVH_KEYS, LBVH_KEYS_OUT,
    LBVH_PARENTS, LBVH_RADIX_BITS, LBVH_RADIX_BLOCK, LBVH_TRIANGLES, LBVH_VALUES, LBVH_VALUES_OUT,
};
use crate::vk::frame_ring::FrameRing;
use crate::vk::pipeline::{bind_compute, compute_pipeline, pipeline_layout, DescriptorSet, Specialization};
use crate::vk::timer::GpuTimer;
use crate::vk::{memory_barrier, Buffer, Context};

/// Mirrors `Push` in glsl/lbvh/lbvh.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    count: u32,
    shift: u32,
    blocks: u32,
    pad: u32,
    lo: [f32; 3],
    pad1: f32,
    scale: [f32; 3],
    pad2: f32,
}

/// Key bits sorted: 30-bit Morton codes, whole passes.
const KEY_BITS: u32 = 30;
const NO_PARENT: u32 = u32::MAX;

/// What the device built and what it cost.
pub struct DeviceBuild {
    /// Karras's tree as a [`Bvh`] (children adjacent, leaves of one triangle).
    pub bvh: Bvh,
    /// The sorted keys (the tests compare them with the host's).
    pub keys: Vec<u32>,
    /// GPU ms per step: morton, sort, hierarchy, bounds.
    pub pass_ms: Vec<(&'static str, f64)>,
    /// Host ms of the step the device does not: the centroid bounds.
    pub host_ms: f64,
}

/// The centroid bounds' low corner and the scale mapping them onto 1024 cells per axis.
fn grid(tris: &[[Vec3; 3]]) -> (Vec3, Vec3) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in tris {
        let c = centroid(t);
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let ext = hi - lo;
    let scale = Vec3::select(ext.cmpgt(Vec3::ZERO), Vec3::splat(1024.0) / ext, Vec3::ZERO);
    (lo, scale)
}

/// As glsl/lbvh/morton.comp computes it (sum, then divide).
fn centroid(t: &[Vec3; 3]) -> Vec3 {
    (t[0] + t[1] + t[2]) / 3.0
}

fn spread(v: u32) -> u32 {
    let v = (v | (v << 16)) & 0x0300_00FF;
    let v = (v | (v << 8)) & 0x0300_F00F;
    let v = (v | (v << 4)) & 0x030C_30C3;
    (v | (v << 2)) & 0x0924_9249
}

/// A centroid's Morton code in the grid (as glsl/lbvh/morton.comp).
fn morton(c: Vec3, lo: Vec3, scale: Vec3) -> u32 {
    let q = ((c - lo) * scale).clamp(Vec3::ZERO, Vec3::splat(1023.0));
    let q = [q.x as u32, q.y as u32, q.z as u32];
    spread(q[0]) << 2 | spread(q[1]) << 1 | spread(q[2])
}

/// Length of the common prefix of sorted keys at positions a and b (Karras's delta); -1 outside.
fn delta(keys: &[u32], a: i64, b: i64) -> i64 {
    if b < 0 || b >= keys.len() as i64 {
        return -1;
    }
    match keys[a as usize] ^ keys[b as usize] {
        0 => 32 + ((a ^ b) as u32).leading_zeros() as i64,
        x => x.leading_zeros() as i64,
    }
}

/// Karras's children of every internal node over sorted `keys` (internal nodes 0 .. n - 2, leaf k is
/// node n - 1 + k): what glsl/lbvh/hierarchy.comp computes.
pub fn hierarchy(keys: &[u32]) -> Vec<[u32; 2]> {
    let n = keys.len() as i64;
    (0..(n - 1).max(0))
        .map(|i| {
            let d = if delta(keys, i, i + 1) > delta(keys, i, i - 1) { 1 } else { -1 };
            let dmin = delta(keys, i, i - d);
            let mut lmax = 2;
            while delta(keys, i, i + lmax * d) > dmin {
                lmax *= 2;
            }
            let (mut l, mut t) = (0, lmax / 2);
            while t >= 1 {
                if delta(keys, i, i + (l + t) * d) > dmin {
                    l += t;
                }
                t /= 2;
            }
            let j = i + l * d;
            let dnode = delta(keys, i, j);
            let (mut s, mut div) = (0, 2);
            loop {
                let t = (l + div - 1) / div;
                if delta(keys, i, i + (s + t) * d) > dnode {
                    s += t;
                }
                if t <= 1 {
                    break;
                }
                div *= 2;
            }
            let gamma = i + s * d + d.min(0);
            let left = if i.min(j) == gamma { n - 1 + gamma } else { gamma };
            let right = if i.max(j) == gamma + 1 { n - 1 + gamma + 1 } else { gamma + 1 };
            [left as u32, right as u32]
        })
        .collect()
}

/// The host's LBVH: the same keys, a stable sort, the same hierarchy. Returns (sorted keys, triangle
/// order, children).
pub fn reference(tris: &[[Vec3; 3]]) -> (Vec<u32>, Vec<u32>, Vec<[u32; 2]>) {
    let (lo, scale) = grid(tris);
    let mut pairs: Vec<(u32, u32)> =
        tris.iter().enumerate().map(|(i, t)| (morton(centroid(t), lo, scale), i as u32)).collect();
    pairs.sort_by_key(|p| p.0);
    let keys: Vec<u32> = pairs.iter().map(|p| p.0).collect();
    let children = hierarchy(&keys);
    (keys, pairs.iter().map(|p| p.1).collect(), children)
}

/// [`reference`] with its boxes, as a [`Bvh`] (what the device's build must equal).
pub fn reference_bvh(tris: &[[Vec3; 3]]) -> Result<Bvh> {
    let (_, order, children) = reference(tris);
    let n = order.len();
    let mut boxes = vec![[0.0f32; 6]; (2 * n).saturating_sub(1)];
    fn fill(
        node: usize,
        n: usize,
        tris: &[[Vec3; 3]],
        order: &[u32],
        children: &[[u32; 2]],
        boxes: &mut [[f32; 6]],
    ) {
        let (lo, hi) = if node >= n - 1 {
            let t = &tris[order[node - (n - 1)] as usize];
            (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
        } else {
            let [l, r] = children[node].map(|c| c as usize);
            fill(l, n, tris, order, children, boxes);
            fill(r, n, tris, order, children, boxes);
            let (a, b) = (boxes[l], boxes[r]);
            (
                Vec3::new(a[0], a[1], a[2]).min(Vec3::new(b[0], b[1], b[2])),
                Vec3::new(a[3], a[4], a[5]).max(Vec3::new(b[3], b[4], b[5])),
            )
        };
        boxes[node] = [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z];
    }
    if n > 0 {
        fill(0, n, tris, &order, &children, &mut boxes);
    }
    to_bvh(&children, &boxes, order)
}

/// Karras's node numbering (children per internal node, a box per node, the triangle order) as a
/// [`Bvh`]: depth first, each node's two children adjacent, leaves of one triangle.
pub fn to_bvh(children: &[[u32; 2]], boxes: &[[f32; 6]], order: Vec<u32>) -> Result<Bvh> {
    let n = order.len();
    if n == 0 {
        return Ok(Bvh::default());
    }
    ensure!(
        children.len() == n - 1 && boxes.len() == 2 * n - 1,
        "LBVH: {n} leaves need {} internal nodes",
        n - 1
    );
    let mut seen = vec![false; 2 * n - 1];
    let node = |src: usize, left_or_first: u32, count: u32| {
        let b = boxes[src];
        BvhNode { min: [b[0], b[1], b[2]], left_or_first, max: [b[3], b[4], b[5]], count }
    };
    let leaf = |src: usize| src >= n - 1;
    let mut nodes = Vec::with_capacity(2 * n - 1);
    nodes.push(node(0, 0, 0));
    // (source node, slot)
    let mut stack = vec![(0usize, 0usize)];
    while let Some((src, at)) = stack.pop() {
        // A node reached twice (or out of range) is not a tree: stop before a cycle grows the stack.
        ensure!(
            src < seen.len() && !std::mem::replace(&mut seen[src], true),
            "LBVH: node {src} is not in a tree"
        );
        if leaf(src) {
            nodes[at] = node(src, (src - (n - 1)) as u32, 1);
            continue;
        }
        let first = nodes.len();
        nodes[at] = node(src, first as u32, 0);
        let [l, r] = children[src];
        nodes.push(node(l as usize, 0, 0));
        nodes.push(node(r as usize, 0, 0));
        stack.push((r as usize, first + 1));
        stack.push((l as usize, first));
    }
    ensure!(nodes.len() == 2 * n - 1, "LBVH: {} of {} nodes reached from the root", nodes.len(), 2 * n - 1);
    Ok(Bvh { nodes, prim_indices: order })
}

/// The builder's pipelines, sets and buffers for one build (destroyed after it).
struct Objects {
    buffers: Vec<Buffer>,
    sets: Vec<DescriptorSet>,
    layout: vk::PipelineLayout,
    pipelines: Vec<vk::Pipeline>,
    timer: GpuTimer,
}

impl Objects {
    fn destroy(&mut self, ctx: &Context) {
        unsafe {
            for p in self.pipelines.drain(..) {
                ctx.device.destroy_pipeline(p, None);
            }
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        for s in &mut self.sets {
            s.destroy(ctx);
        }
        for b in &mut self.buffers {
            b.destroy(ctx);
        }
        self.timer.destroy(ctx);
    }
}

/// Indices into `Objects::buffers`.
const TRIS: usize = 0;
const KEYS: usize = 1;
const VALUES: usize = 2;
const KEYS_OUT: usize = 3;
const VALUES_OUT: usize = 4;
const HIST: usize = 5;
const CHILDREN: usize = 6;
const PARENTS: usize = 7;
const BOXES: usize = 8;
const FLAGS: usize = 9;
const READ_KEYS: usize = 10;
const READ_VALUES: usize = 11;
const READ_CHILDREN: usize = 12;
const READ_BOXES: usize = 13;

/// Builds an LBVH over `tris` on the device and reads it back.
pub fn build_on_device(ctx: &Context, tris: &[[Vec3; 3]]) -> Result<DeviceBuild> {
    let n = tris.len();
    ensure!((1..1 << 30).contains(&n), "device LBVH over {n} triangles: 1 to 2^30 supported");
    let t0 = std::time::Instant::now();
    let (lo, scale) = grid(tris);
    let host_ms = t0.elapsed().as_secs_f64() * 1e3;
    let mut objects = Objects {
        buffers: Vec::new(),
        sets: Vec::new(),
        layout: vk::PipelineLayout::null(),
        pipelines: Vec::new(),
        timer: GpuTimer::empty(),
    };
    let r = run(ctx, tris, lo, scale, &mut objects);
    objects.destroy(ctx);
    let (bvh, keys, pass_ms) = r?;
    Ok(DeviceBuild { bvh, keys, pass_ms, host_ms })
}

type Built = (Bvh, Vec<u32>, Vec<(&'static str, f64)>);

fn run(ctx: &Context, tris: &[[Vec3; 3]], lo: Vec3, scale: Vec3, o: &mut Objects) -> Result<Built> {
    let n = tris.len();
    let blocks = n.div_ceil(LBVH_RADIX_BLOCK as usize);
    let nodes = 2 * n - 1;
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let (src, dst) = (vk::BufferUsageFlags::TRANSFER_SRC, vk::BufferUsageFlags::TRANSFER_DST);
    o.buffers.push(Buffer::with_data(ctx, "LBVH triangles", bytemuck::cast_slice(tris), storage)?);
    let sizes: [(&str, usize, vk::BufferUsageFlags); 9] = [
        ("LBVH keys", 4 * n, storage | src),
        ("LBVH triangle order", 4 * n, storage | src),
        ("LBVH keys (sort pass)", 4 * n, storage),
        ("LBVH triangle order (sort pass)", 4 * n, storage),
        ("LBVH radix histogram", 4 * (1 << LBVH_RADIX_BITS) * blocks, storage),
        ("LBVH children", 8 * (n - 1).max(1), storage | src),
        ("LBVH parents", 4 * nodes, storage | dst),
        ("LBVH boxes", 24 * nodes, storage | src),
        ("LBVH visit counters", 4 * (n - 1).max(1), storage | dst),
    ];
    for (name, bytes, usage) in sizes {
        o.buffers.push(Buffer::new(ctx, name, bytes as u64, usage, MemoryLocation::GpuOnly)?);
    }
    for (name, bytes) in [
        ("LBVH keys (read back)", 4 * n),
        ("LBVH triangle order (read back)", 4 * n),
        ("LBVH children (read back)", 8 * (n - 1).max(1)),
        ("LBVH boxes (read back)", 24 * nodes),
    ] {
        o.buffers.push(Buffer::new(ctx, name, bytes as u64, dst, MemoryLocation::GpuToCpu)?);
    }
    let raw = |k: usize| o.buffers[k].raw;
    let fixed = [
        (LBVH_TRIANGLES, raw(TRIS)),
        (LBVH_HISTOGRAM, raw(HIST)),
        (LBVH_CHILDREN, raw(CHILDREN)),
        (LBVH_PARENTS, raw(PARENTS)),
        (LBVH_BOXES, raw(BOXES)),
        (LBVH_FLAGS, raw(FLAGS)),
    ];
    // The second set swaps the key/value pairs: sort passes alternate between them.
    let pairs = [
        ("LBVH set", KEYS, VALUES, KEYS_OUT, VALUES_OUT),
        ("LBVH set (swapped)", KEYS_OUT, VALUES_OUT, KEYS, VALUES),
    ];
    for (name, a, va, b, vb) in pairs {
        let mut bindings = fixed.to_vec();
        bindings.extend([
            (LBVH_KEYS, raw(a)),
            (LBVH_VALUES, raw(va)),
            (LBVH_KEYS_OUT, raw(b)),
            (LBVH_VALUES_OUT, raw(vb)),
        ]);
        o.sets.push(DescriptorSet::storage_buffers(ctx, name, &bindings)?);
    }
    o.layout = pipeline_layout(ctx, "LBVH layout", &[o.sets[0].layout], std::mem::size_of::<Push>() as u32)?;
    for shader in ["morton", "radix_count", "radix_scan", "radix_scatter", "hierarchy", "bounds"] {
        let p = compute_pipeline(ctx, &format!("lbvh/{shader}.comp"), o.layout, &Specialization::new(&[]))?;
        o.pipelines.push(p);
    }
    o.timer = GpuTimer::new(ctx, 4)?;
    let mut ring = FrameRing::new(1, "LBVH build")?;
    let result = (|| {
        ring.begin(0)?;
        let readback = ctx.one_shot("LBVH build", |cmd| {
            ring.record_uploads(ctx, cmd, 0)?;
            record(ctx, cmd, o, n, blocks, lo, scale);
            let rb = o.timer.download(&mut ring, 0)?;
            ring.record_downloads(ctx, cmd, 0)?;
            Ok(rb)
        })?;
        let pass_ms = readback.ms(&ring, 0)?;
        let keys: Vec<u32> = bytemuck::pod_collect_to_vec(o.buffers[READ_KEYS].read()?);
        let order: Vec<u32> = bytemuck::pod_collect_to_vec(o.buffers[READ_VALUES].read()?);
        let children: Vec<[u32; 2]> =
            bytemuck::pod_collect_to_vec(&o.buffers[READ_CHILDREN].read()?[..8 * (n - 1)]);
        let boxes: Vec<[f32; 6]> = bytemuck::pod_collect_to_vec(o.buffers[READ_BOXES].read()?);
        Ok((to_bvh(&children, &boxes, order)?, keys, pass_ms))
    })();
    ring.destroy(ctx);
    result
}

fn record(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    o: &mut Objects,
    n: usize,
    blocks: usize,
    lo: Vec3,
    scale: Vec3,
) {
    let d = &ctx.device;
    let mut push = Push {
        count: n as u32,
        blocks: blocks as u32,
        lo: lo.to_array(),
        scale: scale.to_array(),
        ..Default::default()
    };
    let groups = |items: usize| (items as u32).div_ceil(LBVH_GROUP);
    let between = || {
        memory_barrier(
            ctx,
            cmd,
            (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            ),
        )
    };
    let dispatch = |pipeline: usize, set: usize, push: &Push, groups: u32| unsafe {
        bind_compute(ctx, cmd, o.pipelines[pipeline], o.layout, &[o.sets[set].set]);
        d.cmd_push_constants(cmd, o.layout, vk::ShaderStageFlags::ALL, 0, bytemuck::bytes_of(push));
        d.cmd_dispatch(cmd, groups, 1, 1);
    };
    o.timer.begin_frame(ctx, cmd);
    unsafe {
        d.cmd_fill_buffer(cmd, o.buffers[PARENTS].raw, 0, vk::WHOLE_SIZE, NO_PARENT);
        d.cmd_fill_buffer(cmd, o.buffers[FLAGS].raw, 0, vk::WHOLE_SIZE, 0);
    }
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::CLEAR, vk::AccessFlags2::TRANSFER_WRITE),
        (
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
        ),
    );
    let t = o.timer.begin(ctx, cmd, "lbvh morton");
    dispatch(0, 0, &push, groups(n));
    if let Some(t) = t {
        o.timer.end(ctx, cmd, t);
    }
    between();
    let t = o.timer.begin(ctx, cmd, "lbvh sort");
    // An even number of passes: the sorted pairs end where the first pass read them.
    let passes = KEY_BITS.div_ceil(LBVH_RADIX_BITS).next_multiple_of(2);
    for pass in 0..passes {
        push.shift = pass * LBVH_RADIX_BITS;
        let set = pass as usize % 2;
        dispatch(1, set, &push, groups(blocks));
        between();
        dispatch(2, set, &push, 1);
        between();
        dispatch(3, set, &push, groups(blocks));
        between();
    }
    if let Some(t) = t {
        o.timer.end(ctx, cmd, t);
    }
    let t = o.timer.begin(ctx, cmd, "lbvh hierarchy");
    dispatch(4, 0, &push, groups(n - 1));
    if let Some(t) = t {
        o.timer.end(ctx, cmd, t);
    }
    between();
    let t = o.timer.begin(ctx, cmd, "lbvh bounds");
    dispatch(5, 0, &push, groups(n));
    if let Some(t) = t {
        o.timer.end(ctx, cmd, t);
    }
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
        (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ),
    );
    for (from, to) in
        [(KEYS, READ_KEYS), (VALUES, READ_VALUES), (CHILDREN, READ_CHILDREN), (BOXES, READ_BOXES)]
    {
        let size = o.buffers[to].size.min(o.buffers[from].size);
        unsafe {
            d.cmd_copy_buffer(
                cmd,
                o.buffers[from].raw,
                o.buffers[to].raw,
                &[vk::BufferCopy::default().size(size)],
            )
        };
    }
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
        (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Karras 2012, figure 3's eight keys: the root splits between the fourth and fifth (the first
    /// differing bit), each internal node's children are as the paper draws them.
    #[test]
    fn hierarchy_of_the_papers_example() {
        let keys = [0b00001, 0b00010, 0b00100, 0b00101, 0b10011, 0b11000, 0b11001, 0b11110];
        let leaf = |k: u32| 7 + k;
        let c = hierarchy(&keys);
        assert_eq!(c[0], [3, 4]);
        assert_eq!(c[3], [1, 2], "node 3 covers keys 0..=3 and splits after key 1");
        assert_eq!(c[1], [leaf(0), leaf(1)]);
        assert_eq!(c[2], [leaf(2), leaf(3)]);
        assert_eq!(c[4], [leaf(4), 5]);
        assert_eq!(c[5], [6, leaf(7)]);
        assert_eq!(c[6], [leaf(5), leaf(6)]);
        // Equal keys split by position: still a tree over every leaf.
        let bvh = to_bvh(&hierarchy(&[7; 5]), &[[0.0; 6]; 9], (0..5).collect()).unwrap();
        assert_eq!(bvh.nodes.len(), 9);
        assert_eq!(bvh.nodes.iter().filter(|n| n.count == 1).count(), 5);
    }
}
