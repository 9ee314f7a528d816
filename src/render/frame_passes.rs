//! The frame's passes as built for one configuration, with the targets they declare: rebuilt when the
//! configuration changes, rebound on resize, and recorded in order, each when its per-frame predicate
//! lets it.

use anyhow::{Context as _, Result};
use ash::vk;

use super::frame::{Access, Recorder, Use};
use super::passes::{
    self, antialias::final_ldr, composite::HDR, inject::Injected, Creation, FrameState, Pass, PassDesc,
    Recording, Upstream,
};
use super::shading::{SceneNeeds, ShadingConfig};
use super::targets::Targets;
use super::tracer::Tracer;
use crate::gpu::GpuScene;
use crate::vk::Context;

/// The debug name of the first frame's submissions on a device that compiles on first use.
pub(super) const COMPILING: &str = "frame: first use (compiling)";

/// A pass of the current frame with what it declared.
struct Recorded {
    desc: &'static PassDesc,
    uses: Vec<Use>,
    pass: Box<dyn Pass>,
}

pub(super) struct FramePasses {
    pub extent: vk::Extent2D,
    pub needs: SceneNeeds,
    /// The configuration the passes were built for.
    pub config: Option<ShadingConfig>,
    passes: Vec<Recorded>,
    pub targets: Targets,
    /// Test fault injection into the HDR frame (`Renderer::inject_radiance`).
    pub injection: Vec<Injected>,
    /// The passes were (re)created since the last recorded frame, and whether that frame was their first:
    /// lavapipe compiles a shader on first use, inside the GPU timestamps, so that frame's times say
    /// nothing of the passes' cost (the budget ignores them).
    pub passes_new: bool,
    pub recorded_cold: bool,
}

/// The readback and the viewer's blit copy these out of the frame: its
/// final LDR image (anti-aliased, or tone mapping's) and the radiance.
fn outputs(config: &ShadingConfig) -> [Use; 2] {
    [Use::image(final_ldr(config), Access::TransferRead), Use::image(&HDR, Access::TransferRead)]
}

impl FramePasses {
    pub fn new(extent: vk::Extent2D, needs: SceneNeeds) -> FramePasses {
        FramePasses {
            extent,
            needs,
            config: None,
            passes: Vec::new(),
            targets: Targets::empty(extent),
            injection: Vec::new(),
            passes_new: false,
            recorded_cold: false,
        }
    }

    /// Recreates the targets at `extent` and rebinds the passes to them (the caller has waited for idle).
    pub fn resize(&mut self, ctx: &Context, extent: vk::Extent2D) -> Result<()> {
        self.extent = extent;
        let uses: Vec<Use> = self.passes.iter().flat_map(|p| p.uses.iter().copied()).collect();
        match self.config {
            Some(config) => self.allocate_targets(ctx, &config, &uses)?,
            None => {
                self.targets.destroy(ctx);
                self.targets = Targets::empty(extent);
            }
        }
        for p in &self.passes {
            p.pass.bind(ctx, &self.targets);
        }
        Ok(())
    }

    /// Allocates exactly the targets `uses` (the passes' declarations) and the outputs of `config` name.
    fn allocate_targets(&mut self, ctx: &Context, config: &ShadingConfig, uses: &[Use]) -> Result<()> {
        self.targets.destroy(ctx);
        let all: Vec<Use> = uses.iter().copied().chain(outputs(config)).collect();
        self.targets = Targets::new(ctx, self.extent, &all)?;
        Ok(())
    }

    /// Destroys the passes (the caller has waited for idle).
    pub fn clear(&mut self, ctx: &Context) {
        for mut p in self.passes.drain(..) {
            p.pass.destroy(ctx);
        }
        self.config = None;
    }

    /// Builds the passes of `config` and their targets; returns the passes it leaves out, with why.
    pub fn build(
        &mut self,
        ctx: &Context,
        config: ShadingConfig,
        gpu: &GpuScene,
        tracer: Option<&dyn Tracer>,
    ) -> Result<Vec<String>> {
        self.clear(ctx);
        let mut left_out = Vec::new();
        let mut chosen = Vec::new();
        for desc in passes::frame(&config) {
            match (desc.skip)(&config) {
                Some(why) => left_out.push(format!("{}: {why}", desc.name)),
                None => chosen.push(desc),
            }
        }
        // Each pass sees what the passes before it write (its inputs' handles).
        let mut upstream = vec![Upstream::default()];
        let mut uses: Vec<Vec<Use>> = Vec::new();
        for d in &chosen {
            let before = upstream.last().expect("one per pass and the start");
            let u = (d.uses)(&config, before);
            let mut after = before.clone();
            after.add(&u);
            upstream.push(after);
            uses.push(u);
        }
        // Targets first (passes bind them), from what the passes declare.
        self.allocate_targets(ctx, &config, &uses.iter().flatten().copied().collect::<Vec<_>>())?;
        for ((desc, uses), upstream) in chosen.into_iter().zip(uses).zip(&upstream) {
            let init = Creation { ctx, config: &config, gpu, targets: &self.targets, tracer, upstream };
            let pass = (desc.create)(&init).with_context(|| format!("creating pass {}", desc.name))?;
            self.passes.push(Recorded { desc, uses, pass });
        }
        self.passes_new = true;
        self.config = Some(config);
        Ok(left_out)
    }

    /// Names of the passes a frame in `state` records, in order.
    pub fn names(&self, state: &FrameState) -> Vec<&'static str> {
        self.passes.iter().filter(|p| (p.desc.this_frame)(state).is_none()).map(|p| p.desc.name).collect()
    }

    /// Records the passes a frame in `state` runs.
    pub fn record(&self, rec: &mut Recorder, cx: &Recording, state: &FrameState) -> Result<()> {
        self.record_each(rec, cx, state, |_, _| Ok(()))
    }

    /// `record` for the first frame of these passes on a device that compiles each pipeline on first
    /// use (lavapipe): each pass goes out in a submission of its own (`rec.cmd` from `Context::begin_spare`,
    /// a new one after each), and the log says which pass compiled and how long it took; the frame's
    /// image is the same.
    pub fn record_compiling(&self, rec: &mut Recorder, cx: &Recording, state: &FrameState) -> Result<()> {
        let ctx = cx.ctx;
        let n = self.names(state).len();
        log::info!(
            "frame: compiling the shaders of {n} passes: a software device compiles each pipeline on first use \
             (seconds each the first time; Mesa's disk cache keeps them for later runs)"
        );
        crate::progress::stage(format!("compiling the shaders of {n} passes"));
        let started = std::time::Instant::now();
        let (mut k, mut last) = (0, started);
        self.record_each(rec, cx, state, |rec, name| {
            ctx.submit_spare(rec.cmd)?;
            rec.cmd = ctx.begin_spare(COMPILING)?;
            k += 1;
            crate::progress::percent(k, n);
            let now = std::time::Instant::now();
            let (pass_s, all_s) = ((now - last).as_secs_f64(), (now - started).as_secs_f64());
            log::info!("frame: [{k}/{n}] {name} compiled and ran in {pass_s:.1} s ({all_s:.1} s in all)");
            last = now;
            Ok(())
        })
    }

    /// Records the passes a frame in `state` runs, calling `after` behind each.
    fn record_each(
        &self,
        rec: &mut Recorder,
        cx: &Recording,
        state: &FrameState,
        mut after: impl FnMut(&mut Recorder, &'static str) -> Result<()>,
    ) -> Result<()> {
        for p in &self.passes {
            if (p.desc.this_frame)(state).is_some() {
                continue;
            }
            rec.pass(p.desc.name, p.pass.stage(), &p.uses, |cmd| {
                p.pass.record(cx, cmd);
                Ok(())
            })?;
            after(rec, p.desc.name)?;
        }
        Ok(())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.clear(ctx);
        self.targets.destroy(ctx);
    }
}
