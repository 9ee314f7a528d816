//! Ray microbenchmark (`bench --rays`): traces fixed ray sets (sets.rs) through one tracer with
//! glsl/passes/rays.glsl, one invocation per ray, GPU-timed, and reads back every hit so two tracers
//! can be compared ray by ray. The compute tracer also has a statistics variant (nodes and triangles
//! per ray).

pub mod sets;

use anyhow::{Context as _, Result};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;

use super::kernel::Kernel;
use super::shading::Backend;
use super::tracer::Tracer;
use crate::gpu::shared::{
    BENCH_RAY_STRIDE, BENCH_RESULT_STRIDE, RAYS_IN, RAYS_OUT, RAYS_STATS, SPEC_TRACE_PACKET,
    TRACE_PACKET_CLOSEST, TRACE_PACKET_DEFAULT, TRACE_PACKET_SHADOW,
};
use crate::gpu::GpuScene;
use crate::vk::pipeline::{pipeline_layout, DescriptorSet, Specialization};
use crate::vk::{copy_to_host_barrier, memory_barrier, Buffer, Context};

/// One ray (glsl/rays.comp `BenchRay`), in render-origin-relative world space.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct BenchRay {
    pub origin: [f32; 3],
    pub tmax: f32,
    pub dir: [f32; 3],
    pub pad: u32,
}
const _: () = assert!(std::mem::size_of::<BenchRay>() == BENCH_RAY_STRIDE as usize);

/// What one ray hit (glsl/rays.comp `BenchResult`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct BenchResult {
    /// Closest-hit distance (closest-hit rays; 0 for shadow rays).
    pub t: f32,
    pub instance: u32,
    pub primitive: u32,
    /// 1: hit (closest-hit rays) or blocked (shadow rays).
    pub hit: u32,
    /// The hit point moved off the surface (closest-hit rays), or the
    /// transmittance (shadow rays).
    pub next: [f32; 3],
    pub pad0: f32,
    /// Geometric normal facing the ray (closest-hit rays).
    pub normal: [f32; 3],
    pub pad1: f32,
}
const _: () = assert!(std::mem::size_of::<BenchResult>() == BENCH_RESULT_STRIDE as usize);

/// One ray set traced: the last repetition's results, the GPU time of each
/// measured repetition, and the traversal statistics when asked for.
pub struct TraceRun {
    pub results: Vec<BenchResult>,
    pub gpu_ms: Vec<f64>,
    /// Per ray (compute tracer, stats variant): nodes visited, triangles
    /// tested, nodes the ray itself entered (fewer than the nodes visited
    /// in packet traversal, where the subgroup visits the union), 0.
    pub stats: Option<Vec<[u32; 4]>>,
}

impl TraceRun {
    /// Median GPU time of the measured repetitions (NaN without timestamps).
    pub fn median_ms(&self) -> f64 {
        let mut t = self.gpu_ms.clone();
        t.sort_by(|a, b| a.total_cmp(b));
        t.get(t.len() / 2).copied().unwrap_or(f64::NAN)
    }

    /// Million rays per second at the median time.
    pub fn mrays_per_s(&self) -> f64 {
        self.results.len() as f64 / (self.median_ms() * 1e3)
    }

    /// Mean nodes visited, triangles tested and nodes entered per ray.
    pub fn mean_stats(&self) -> Option<(f64, f64, f64)> {
        let s = self.stats.as_ref()?;
        let n = s.len().max(1) as f64;
        let sum = |k: usize| s.iter().map(|v| v[k] as u64).sum::<u64>() as f64 / n;
        Some((sum(0), sum(1), sum(2)))
    }
}

/// Which rays the compute tracer traces as subgroup packets
/// (glsl/trace/compute_packet.glsl) rather than lane by lane: the value of
/// the SPEC_TRACE_PACKET specialization constant.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Traversal {
    /// What the tracing passes use (TRACE_PACKET_DEFAULT).
    #[default]
    Default,
    /// Every ray on its own.
    Lane,
    /// Every ray kind as packets.
    Packet,
}

impl Traversal {
    pub fn spec_value(self) -> u32 {
        match self {
            Traversal::Default => TRACE_PACKET_DEFAULT,
            Traversal::Lane => 0,
            Traversal::Packet => TRACE_PACKET_SHADOW | TRACE_PACKET_CLOSEST,
        }
    }
}

/// The first `bytes` of device-local `src`, copied through `readback`
/// (host-visible, at least as large) after the work that wrote it.
fn read_back(ctx: &Context, src: &Buffer, readback: &Buffer, bytes: usize) -> Result<Vec<u8>> {
    if bytes == 0 {
        return Ok(Vec::new());
    }
    ctx.one_shot("read back bench rays", |cmd| {
        let region = [vk::BufferCopy::default().size(bytes as u64)];
        unsafe { ctx.device.cmd_copy_buffer(cmd, src.raw, readback.raw, &region) };
        copy_to_host_barrier(ctx, cmd);
        Ok(())
    })?;
    Ok(readback.read()?[..bytes].to_vec())
}

/// The pipelines tracing ray sets through one tracer.
pub struct RayRig {
    set: DescriptorSet,
    layout: vk::PipelineLayout,
    kernel: Kernel,
    /// The compute tracer's statistics variant.
    stats: Option<Kernel>,
    timestamps: vk::QueryPool,
    backend: Backend,
    /// Untimed tracing before the timed repetitions of each set (none by
    /// default). A GPU idles at a low clock: an H200 idled at 345 MHz, and
    /// the first set a `bench --rays` process timed read 2.2x slower than
    /// the same set timed after other work.
    pub warm_up: std::time::Duration,
}

impl RayRig {
    pub fn new(ctx: &Context, gpu: &GpuScene, tracer: &dyn Tracer, traversal: Traversal) -> Result<RayRig> {
        let backend = tracer.backend();
        let rig = RayRig {
            set: DescriptorSet::null(),
            layout: vk::PipelineLayout::null(),
            kernel: Kernel::Compute(vk::Pipeline::null()),
            stats: None,
            timestamps: vk::QueryPool::null(),
            backend,
            warm_up: std::time::Duration::ZERO,
        };
        crate::vk::built(ctx, rig, |r| r.fill(ctx, gpu, tracer, traversal))
    }

    fn fill(
        &mut self,
        ctx: &Context,
        gpu: &GpuScene,
        tracer: &dyn Tracer,
        traversal: Traversal,
    ) -> Result<()> {
        use crate::vk::pipeline::Binding;
        let sb = Binding::one(vk::DescriptorType::STORAGE_BUFFER);
        self.set = DescriptorSet::numbered(ctx, "rays", &[(RAYS_IN, sb), (RAYS_OUT, sb), (RAYS_STATS, sb)])?;
        self.layout =
            pipeline_layout(ctx, "rays layout", &[gpu.set.layout, self.set.layout, tracer.set().layout], 8)?;
        // The ray query's shader has no such constant: Vulkan ignores the entry.
        let spec = Specialization::new(&[(SPEC_TRACE_PACKET, traversal.spec_value())]);
        self.kernel = tracer.kernel(ctx, "rays", self.layout, &spec)?;
        if self.backend == Backend::Compute {
            self.stats = Some(Kernel::compute(ctx, "rays_compute_stats", self.layout, &spec)?);
        }
        if ctx.caps.timestamps {
            let pool = unsafe {
                ctx.device.create_query_pool(
                    &vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(2),
                    None,
                )?
            };
            ctx.name(pool, "rays timestamps");
            self.timestamps = pool;
        }
        Ok(())
    }

    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// Traces `rays` (shadow: any-hit transmittance rays, else closest
    /// hit) unmeasured (once, and for `warm_up`), then `reps` times timed; with `stats` (compute
    /// tracer only) one more pass through the statistics variant.
    #[allow(clippy::too_many_arguments)]
    pub fn trace(
        &self,
        ctx: &Context,
        gpu: &GpuScene,
        tracer: &dyn Tracer,
        rays: &[BenchRay],
        shadow: bool,
        reps: usize,
        stats: bool,
    ) -> Result<TraceRun> {
        let n = rays.len().max(1);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        // The tracers write device-local memory, as a frame's passes do;
        // host-visible memory would time the bus on a discrete GPU (on an
        // H200, 48-byte results written to host memory capped every tracer
        // at 0.2-0.5 Grays/s). Copied to `readback` after the timed dispatches.
        let out = storage | vk::BufferUsageFlags::TRANSFER_SRC;
        let result_bytes = (n * std::mem::size_of::<BenchResult>()) as u64;
        let mut bufs: Vec<Buffer> = Vec::new();
        let run = (|| {
            bufs.push(Buffer::with_data(ctx, "bench rays", bytemuck::cast_slice(rays), storage)?);
            bufs.push(Buffer::new(ctx, "bench ray results", result_bytes, out, MemoryLocation::GpuOnly)?);
            bufs.push(Buffer::new(ctx, "bench ray stats", (n * 16) as u64, out, MemoryLocation::GpuOnly)?);
            let usage = vk::BufferUsageFlags::TRANSFER_DST;
            bufs.push(Buffer::new(ctx, "bench ray readback", result_bytes, usage, MemoryLocation::GpuToCpu)?);
            self.run(
                ctx,
                gpu,
                tracer,
                rays.len(),
                (&bufs[0], &bufs[1], &bufs[2], &bufs[3]),
                shadow,
                reps,
                stats,
            )
        })();
        for b in &mut bufs {
            b.destroy(ctx);
        }
        run
    }

    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        ctx: &Context,
        gpu: &GpuScene,
        tracer: &dyn Tracer,
        count: usize,
        (input, output, counters, readback): (&Buffer, &Buffer, &Buffer, &Buffer),
        shadow: bool,
        reps: usize,
        stats: bool,
    ) -> Result<TraceRun> {
        self.set.write_buffer(ctx, RAYS_IN, input.raw);
        self.set.write_buffer(ctx, RAYS_OUT, output.raw);
        self.set.write_buffer(ctx, RAYS_STATS, counters.raw);
        // Untimed: once, then on for `warm_up`, so that a GPU's clock has
        // left idle before the timed repetitions.
        let start = std::time::Instant::now();
        self.dispatch(ctx, gpu, tracer, &self.kernel, count, shadow)?;
        while start.elapsed() < self.warm_up {
            self.dispatch(ctx, gpu, tracer, &self.kernel, count, shadow)?;
        }
        let mut gpu_ms = Vec::new();
        for _ in 0..reps {
            gpu_ms.push(self.dispatch(ctx, gpu, tracer, &self.kernel, count, shadow)?);
        }
        let results: Vec<BenchResult> = bytemuck::pod_collect_to_vec(&read_back(
            ctx,
            output,
            readback,
            count * size_of::<BenchResult>(),
        )?);
        let stats = match (&self.stats, stats) {
            (Some(k), true) => {
                self.dispatch(ctx, gpu, tracer, k, count, shadow)?;
                Some(bytemuck::pod_collect_to_vec::<u8, [u32; 4]>(&read_back(
                    ctx,
                    counters,
                    readback,
                    count * 16,
                )?))
            }
            _ => None,
        };
        Ok(TraceRun { results, gpu_ms, stats })
    }

    /// One dispatch over `count` rays, waited for; returns its GPU time in ms.
    fn dispatch(
        &self,
        ctx: &Context,
        gpu: &GpuScene,
        tracer: &dyn Tracer,
        kernel: &Kernel,
        count: usize,
        shadow: bool,
    ) -> Result<f64> {
        let timed = self.timestamps != vk::QueryPool::null();
        let stage = kernel.stage();
        ctx.one_shot("trace bench rays", |cmd| {
            let d = &ctx.device;
            let push = [count as u32, shadow as u32];
            unsafe {
                if timed {
                    d.cmd_reset_query_pool(cmd, self.timestamps, 0, 2);
                }
                d.cmd_bind_pipeline(cmd, kernel.bind_point(), kernel.pipeline());
                d.cmd_bind_descriptor_sets(
                    cmd,
                    kernel.bind_point(),
                    self.layout,
                    0,
                    &[gpu.set.set, self.set.set, tracer.set().set],
                    &[],
                );
                d.cmd_push_constants(
                    cmd,
                    self.layout,
                    vk::ShaderStageFlags::ALL,
                    0,
                    bytemuck::cast_slice(&push),
                );
                if timed {
                    d.cmd_write_timestamp2(cmd, stage, self.timestamps, 0);
                }
                match kernel {
                    Kernel::Compute(_) => d.cmd_dispatch(cmd, (count as u32).div_ceil(64), 1, 1),
                    // One launch along x: within the width limits
                    // (maxComputeWorkGroupCount[0] x maxComputeWorkGroupSize[0],
                    // at least 65535 x 128) for sets up to 8.3M rays (4K).
                    Kernel::RayTracing(rt) => rt.trace(ctx, cmd, count as u32, 1),
                }
                if timed {
                    d.cmd_write_timestamp2(cmd, stage, self.timestamps, 1);
                }
            }
            memory_barrier(
                ctx,
                cmd,
                (stage, vk::AccessFlags2::SHADER_WRITE),
                (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ),
            );
            Ok(())
        })?;
        if !timed {
            return Ok(f64::NAN);
        }
        let mut ticks = [0u64; 2];
        unsafe {
            ctx.device.get_query_pool_results(
                self.timestamps,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .context("read the ray benchmark's timestamps")?;
        Ok(ticks[1].saturating_sub(ticks[0]) as f64 * ctx.caps.timestamp_period_ns as f64 * 1e-6)
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.kernel.destroy(ctx);
        if let Some(k) = &mut self.stats {
            k.destroy(ctx);
        }
        unsafe {
            ctx.device.destroy_pipeline_layout(self.layout, None);
            ctx.device.destroy_query_pool(self.timestamps, None);
        }
        self.set.destroy(ctx);
    }
}

crate::destroy_by_method!(RayRig);
