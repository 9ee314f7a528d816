//! `bench --rays`: the ray microbenchmark. Fixed ray sets on the scene (render/rays/sets.rs) traced
//! through our compute BVH tracer and the driver's (its ray query, or its ray-tracing pipeline where it
//! has no ray query, as NVIDIA's driver on some machines), timed with GPU timestamps, compared ray by ray.

use crate::vk::frame_ring::upload_now;
use anyhow::{bail, Context as _, Result};

use super::{load_posed, with_context, GpuOptions, RenderJob};
use crate::gpu::types::GpuFrame;
use crate::gpu::GpuScene;
use crate::render::rays::sets::{self, RayKind};
use crate::render::rays::{BenchRay, RayRig, TraceRun, Traversal};
use crate::render::shading::Backend;
use crate::render::tracer::{self, Tracer};
use crate::scene::Scene;
use crate::vk::{built, Context};

/// `bench --rays` traces each set untimed for this long first (RayRig::warm_up).
const WARM_UP_MS: u64 = 300;

/// Seed of the diffuse-bounce directions (fixed: every run traces the same rays).
pub const DIFFUSE_SEED: u32 = 1;

/// One ray kind traced by both tracers.
pub struct KindReport {
    pub kind: RayKind,
    pub rays: usize,
    pub compute: TraceRun,
    /// The driver's tracer: `driver_backend` (Query or Pipeline).
    pub driver: TraceRun,
    pub driver_backend: Backend,
    /// Indices of the rays on which the two disagree (sets::mismatches).
    pub mismatches: Vec<usize>,
}

impl KindReport {
    /// `rays <kind>: compute <x> Mrays/s, query <y> Mrays/s, ratio <r>`
    /// (`pipeline <y>` where the driver's pipeline traced them).
    pub fn line(&self) -> String {
        let (c, q) = (self.compute.mrays_per_s(), self.driver.mrays_per_s());
        format!(
            "rays {}: compute {c:.3} Mrays/s, {} {q:.3} Mrays/s, ratio {:.2}",
            self.kind.name(),
            self.driver_backend.name(),
            c / q
        )
    }

    /// Ray count, agreement and the compute tracer's traversal statistics.
    pub fn detail(&self) -> String {
        let (nodes, tris, entered) = self.compute.mean_stats().unwrap_or((f64::NAN, f64::NAN, f64::NAN));
        let mut s = format!(
            "  {}: {} rays, {} mismatches between the tracers; compute traversal {nodes:.1} nodes \
             ({entered:.1} entered by the ray), {tris:.1} triangle tests per ray",
            self.kind.name(),
            self.rays,
            self.mismatches.len()
        );
        // The first disagreement, so it can be looked into.
        if let Some(&i) = self.mismatches.first() {
            s.push_str(&format!(
                "\n    first mismatch: ray {i}, compute {:?}, {} {:?}",
                self.compute.results[i],
                self.driver_backend.name(),
                self.driver.results[i]
            ));
        }
        s
    }
}

/// The driver's tracer `bench --rays` compares with for `--backend
/// requested`: auto takes the ray query, else the ray-tracing pipeline.
pub fn driver_backend(ctx: &Context, requested: Backend) -> Result<Backend> {
    let why_not = |has: bool| if has { "has, but --no-rt disabled" } else { "lacks" };
    Ok(match requested {
        Backend::Query if !ctx.rt.ray_query => {
            bail!(
                "bench --rays --backend query: this device {} VK_KHR_ray_query",
                why_not(ctx.caps.ray_query)
            )
        }
        Backend::Pipeline if !ctx.rt.ray_tracing_pipeline => bail!(
            "bench --rays --backend pipeline: this device {} VK_KHR_ray_tracing_pipeline",
            why_not(ctx.caps.ray_tracing_pipeline)
        ),
        Backend::Query | Backend::Pipeline => requested,
        Backend::Compute => bail!(
            "bench --rays compares the compute tracer with the driver's: --backend query, pipeline or auto, \
             not compute"
        ),
        Backend::Auto if ctx.rt.ray_query => Backend::Query,
        Backend::Auto if ctx.rt.ray_tracing_pipeline => Backend::Pipeline,
        Backend::Auto => bail!(
            "bench --rays compares with the driver's ray query or ray-tracing pipeline, and this device {} \
             both (use a device with VK_KHR_ray_query or VK_KHR_ray_tracing_pipeline, without --no-rt)",
            if ctx.caps.ray_query || ctx.caps.ray_tracing_pipeline {
                "has, but --no-rt disabled"
            } else {
                "lacks"
            }
        ),
    })
}

/// The two tracers over one uploaded scene, with their pipelines.
pub struct RayBench {
    pub gpu: GpuScene,
    tracers: Vec<Box<dyn Tracer>>,
    /// One per tracer, in the same order.
    rigs: Vec<RayRig>,
    driver: Backend,
}

impl RayBench {
    /// With the compute tracer's default traversal per ray kind, against
    /// the driver's ray query (else its pipeline).
    pub fn new(ctx: &Context, scene: &Scene) -> Result<RayBench> {
        RayBench::with_traversal(ctx, scene, Traversal::Default, Backend::Auto)
    }

    /// `driver`: the driver's tracer to compare with (see `driver_backend`).
    pub fn with_traversal(
        ctx: &Context,
        scene: &Scene,
        traversal: Traversal,
        driver: Backend,
    ) -> Result<RayBench> {
        let driver = driver_backend(ctx, driver)?;
        let gpu = GpuScene::upload(ctx, scene)?;
        let bench = RayBench { gpu, tracers: Vec::new(), rigs: Vec::new(), driver };
        built(ctx, bench, |bench| {
            if !bench.gpu.skinned.is_empty() {
                bail!(
                    "{}: bench --rays traces static scenes only (this one has skinned meshes, which the \
                     frame's skinning pass would have to deform first)",
                    scene.source.display()
                );
            }
            let frame = GpuFrame { light_count: bench.gpu.light_count, ..Default::default() };
            upload_now(ctx, "frame uniforms", |up| bench.gpu.write_frame(up, &frame))?;
            for backend in [Backend::Compute, driver] {
                bench.tracers.push(tracer::create(ctx, backend, scene, &bench.gpu)?);
                let t = bench.tracers.last().expect("pushed");
                bench.rigs.push(RayRig::new(ctx, &bench.gpu, t.as_ref(), traversal)?);
            }
            Ok(())
        })
    }

    fn run(
        &self,
        ctx: &Context,
        backend: Backend,
        rays: &[BenchRay],
        kind: RayKind,
        reps: usize,
    ) -> Result<TraceRun> {
        let (t, rig) = (self.tracers.iter().zip(&self.rigs))
            .find(|(_, r)| r.backend() == backend)
            .context("tracer missing from the ray benchmark")?;
        rig.trace(ctx, &self.gpu, t.as_ref(), rays, kind.is_shadow(), reps, backend == Backend::Compute)
            .with_context(|| format!("trace the {} rays ({backend:?})", kind.name()))
    }

    /// Traces `rays` of `kind` through both tracers and compares them.
    pub fn kind(&self, ctx: &Context, kind: RayKind, rays: &[BenchRay], reps: usize) -> Result<KindReport> {
        let compute = self.run(ctx, Backend::Compute, rays, kind, reps)?;
        let driver = self.run(ctx, self.driver, rays, kind, reps)?;
        let mismatches = sets::mismatches(kind, &compute.results, &driver.results);
        Ok(KindReport { kind, rays: rays.len(), compute, driver, driver_backend: self.driver, mismatches })
    }

    /// Every kind in order: primary rays from the camera, then shadow and diffuse rays from the compute
    /// tracer's primary hits (both tracers trace the same sets).
    pub fn all(&self, ctx: &Context, scene: &Scene, job: &RenderJob, reps: usize) -> Result<Vec<KindReport>> {
        let camera = job.camera.resolve(scene)?;
        let extent = job.extent()?;
        let primary = sets::primary_rays(&camera, &self.gpu.origin, extent.width, extent.height);
        let p = self.kind(ctx, RayKind::Primary, &primary, reps)?;
        let shadow = sets::shadow_rays(scene, &self.gpu.origin, &p.compute.results)?;
        let diffuse = sets::diffuse_rays(&p.compute.results, DIFFUSE_SEED);
        let s = self.kind(ctx, RayKind::Shadow, &shadow, reps)?;
        let d = self.kind(ctx, RayKind::Diffuse, &diffuse, reps)?;
        Ok(vec![p, s, d])
    }

    /// Untimed tracing of each set before its timed repetitions.
    pub fn warm_up(&mut self, d: std::time::Duration) {
        for rig in &mut self.rigs {
            rig.warm_up = d;
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for rig in &mut self.rigs {
            rig.destroy(ctx);
        }
        for t in &mut self.tracers {
            t.destroy(ctx);
        }
        self.gpu.destroy(ctx);
    }
}

crate::destroy_by_method!(RayBench);

/// `bench --rays`: prints one `rays <kind>:` line per kind, then the
/// details (ray counts, mismatches, traversal statistics).
pub fn rays_command(
    gpu: &GpuOptions,
    job: &RenderJob,
    reps: usize,
    traversal: Traversal,
    driver: Backend,
) -> Result<()> {
    with_context(gpu, |ctx| {
        let (scene, _) = load_posed(job)?;
        let mut bench = RayBench::with_traversal(ctx, &scene, traversal, driver)?;
        bench.warm_up(std::time::Duration::from_millis(WARM_UP_MS));
        let reports = bench.all(ctx, &scene, job, reps);
        bench.destroy(ctx);
        let reports = reports?;
        println!(
            "ray microbenchmark: {} at {}x{} primary rays, median of {reps} repetitions after {WARM_UP_MS} ms untimed (GPU timestamps), \
             compute traversal {traversal:?}",
            scene.source.display(),
            job.width,
            job.height
        );
        for r in &reports {
            println!("{}", r.line());
        }
        for r in &reports {
            println!("{}", r.detail());
        }
        super::check_validation(ctx)
    })
}
