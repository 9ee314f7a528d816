//! A full-screen pass (every pass but `gbuffer`): set 0 the scene, set 1 its images (each binding tied
//! to one declared use), set 2 the tracer's when it traces; one invocation per pixel, or per listed
//! pixel where a select kernel compacts the work (compacted.rs).

use anyhow::Result;
use ash::vk;

use super::compacted::WorkList;
use super::{Creation, Pass, Recording};
use crate::gpu::shared::WORK_HEADER;
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::kernel::Kernel;
use crate::render::targets::{TargetDesc, Targets};
use crate::vk::pipeline::{pipeline_layout, Binding, DescriptorSet, Specialization};
use crate::vk::{built, Context};

/// One set-1 binding: which target, how it is accessed.
#[derive(Clone, Copy)]
pub struct TargetBinding {
    pub binding: u32,
    pub target: &'static TargetDesc,
    pub access: Access,
}

impl TargetBinding {
    pub const fn new(binding: u32, target: &'static TargetDesc, access: Access) -> TargetBinding {
        TargetBinding { binding, target, access }
    }
}

/// The shader of a full-screen pass.
pub enum Shader {
    /// A plain compute shader.
    Compute(&'static str),
    /// A tracing pass: the tracer supplies `{name}_query`, `.rgen`, ...
    Traced(&'static str),
    /// A tracing pass over the pixels the compute shader `select` lists
    /// (compacted.rs; the pass's io has `compacted::list_io()`).
    Listed { select: &'static str, traced: &'static str },
}

/// The declared uses of a full-screen pass with `io`; a traced one also
/// reads the scene geometry and the acceleration data.
pub fn uses(io: &[TargetBinding], traced: bool) -> Vec<Use> {
    let mut u: Vec<Use> = io.iter().map(|i| Use::image(i.target, i.access)).collect();
    if traced {
        u.push(Use::buffer(SharedBuffer::Geometry, Access::ShaderRead));
        u.push(Use::buffer(SharedBuffer::Accel, Access::ShaderRead));
    }
    u
}

/// Uses of a pass accumulating into `accumulation` across frames (`reference`, `terms`, `path`):
/// read-modify-write, so the previous sum is read too.
pub fn accumulating_uses(io: &[TargetBinding], accumulation: &'static TargetDesc) -> Vec<Use> {
    let mut u = uses(io, true);
    u.push(Use::image(accumulation, Access::StorageRead));
    u
}

/// Fails when a variant of the pass's shader declares a storage image with
/// a format qualifier other than its target's format (undefined behaviour).
fn check_formats(name: &str, shader: &Shader, io: &[TargetBinding]) -> Result<()> {
    use crate::gpu::shared::SET_PASS;
    use crate::vk::reflect::{spirv_image_format, storage_image_formats};
    let traced = |s: &str| vec![format!("{s}_query"), format!("{s}_compute"), format!("{s}.rgen")];
    let variants: Vec<String> = match shader {
        Shader::Compute(s) => vec![s.to_string()],
        Shader::Traced(s) => traced(s),
        Shader::Listed { select, traced: s } => [vec![select.to_string()], traced(s)].concat(),
    };
    for v in variants {
        let Ok(words) = crate::vk::pipeline::spirv(&v) else { continue };
        for (set, binding, declared) in storage_image_formats(&words) {
            let Some(i) = io.iter().find(|i| set == SET_PASS && i.binding == binding) else { continue };
            if i.access == Access::Sampled {
                continue;
            }
            if let Some(want) = spirv_image_format(i.target.format).filter(|w| *w != declared) {
                anyhow::bail!(
                    "pass {name}: shader {v} declares binding {binding} with SPIR-V image format {declared}, \
                     but it is bound to '{}' ({:?}, SPIR-V format {want})",
                    i.target.name,
                    i.target.format
                );
            }
        }
    }
    Ok(())
}

pub struct FullScreen {
    io: Vec<TargetBinding>,
    set: DescriptorSet,
    layout: vk::PipelineLayout,
    kernel: Kernel,
    sampler: vk::Sampler,
    traced: bool,
    /// The select kernel and header of a `Shader::Listed` pass.
    work: Option<WorkList>,
    /// Pixels a compute workgroup covers.
    group: [u32; 2],
}

/// The workgroup footprint of a kernel with one invocation per pixel (local size 8x8).
pub const PIXEL_GROUP: [u32; 2] = [8, 8];

impl FullScreen {
    /// Builds the pass (its set, layout and kernel) and binds its targets.
    pub fn create(
        init: &Creation,
        name: &'static str,
        io: Vec<TargetBinding>,
        shader: Shader,
        spec: &Specialization,
    ) -> Result<Box<dyn Pass>> {
        Self::create_grouped(init, name, io, shader, spec, PIXEL_GROUP)
    }

    /// `create` for a compute kernel whose 8x8 workgroups cover `group` pixels (each invocation a
    /// block of them).
    pub fn create_grouped(
        init: &Creation,
        name: &'static str,
        io: Vec<TargetBinding>,
        shader: Shader,
        spec: &Specialization,
        group: [u32; 2],
    ) -> Result<Box<dyn Pass>> {
        let ctx = init.ctx;
        check_formats(name, &shader, &io)?;
        let mut bindings: Vec<(u32, Binding)> = io
            .iter()
            .map(|i| {
                let ty = match i.access {
                    Access::Sampled => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                    _ => vk::DescriptorType::STORAGE_IMAGE,
                };
                (i.binding, Binding::one(ty))
            })
            .collect();
        let select = match shader {
            Shader::Listed { select, .. } => {
                bindings.push((WORK_HEADER, Binding::one(vk::DescriptorType::STORAGE_BUFFER)));
                Some(select)
            }
            _ => None,
        };
        let tracer = match shader {
            Shader::Traced(_) | Shader::Listed { .. } => Some(
                init.tracer.ok_or_else(|| anyhow::anyhow!("pass {name} traces rays but no tracer exists"))?,
            ),
            Shader::Compute(_) => None,
        };
        let pass = FullScreen {
            io,
            set: DescriptorSet::null(),
            layout: vk::PipelineLayout::null(),
            kernel: Kernel::Compute(vk::Pipeline::null()),
            sampler: vk::Sampler::null(),
            traced: tracer.is_some(),
            work: None,
            group,
        };
        // Filled step by step; a failed step destroys what exists.
        let pass = built(ctx, pass, |p| {
            p.set = DescriptorSet::numbered(ctx, &format!("{name} set"), &bindings)?;
            let mut sets = vec![init.gpu.set.layout, p.set.layout];
            sets.extend(tracer.map(|t| t.set().layout));
            p.layout = pipeline_layout(ctx, &format!("{name} layout"), &sets, 0)?;
            p.kernel = match (shader, tracer) {
                (Shader::Traced(s) | Shader::Listed { traced: s, .. }, Some(t)) => {
                    t.kernel(ctx, s, p.layout, spec)
                }
                (Shader::Compute(s) | Shader::Traced(s) | Shader::Listed { traced: s, .. }, _) => {
                    Kernel::compute(ctx, s, p.layout, spec)
                }
            }?;
            let sampler = vk::SamplerCreateInfo::default()
                .mag_filter(vk::Filter::NEAREST)
                .min_filter(vk::Filter::NEAREST)
                .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE);
            p.sampler = unsafe { ctx.device.create_sampler(&sampler, None) }?;
            ctx.name(p.sampler, &format!("{name} point sampler"));
            if let Some(select) = select {
                p.work = Some(WorkList::create(ctx, name, select, p.layout, spec, &p.set)?);
            }
            Ok(())
        })?;
        pass.bind(ctx, init.targets);
        Ok(Box::new(pass))
    }
}

impl Pass for FullScreen {
    fn stage(&self) -> vk::PipelineStageFlags2 {
        match self.work {
            // The select kernel is a compute shader whatever the backend.
            Some(_) => self.kernel.stage() | vk::PipelineStageFlags2::COMPUTE_SHADER,
            None => self.kernel.stage(),
        }
    }

    fn record(&self, cx: &Recording, cmd: vk::CommandBuffer) {
        let mut sets = vec![cx.gpu.set.set, self.set.set];
        if self.traced {
            sets.extend(cx.tracer.map(|t| t.set().set));
        }
        match &self.work {
            Some(w) => w.record(cx.ctx, cmd, &self.kernel, self.layout, &sets, cx.targets.extent),
            None => self.kernel.dispatch(cx.ctx, cmd, self.layout, &sets, cx.targets.extent, self.group),
        }
    }

    fn bind(&self, ctx: &Context, targets: &Targets) {
        for i in &self.io {
            let Some(t) = targets.get(i.target) else { continue };
            match i.access {
                Access::Sampled => self.set.write_image(
                    ctx,
                    i.binding,
                    0,
                    t.view,
                    self.sampler,
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                ),
                _ => self.set.write_image(
                    ctx,
                    i.binding,
                    0,
                    t.view,
                    vk::Sampler::null(),
                    vk::ImageLayout::GENERAL,
                ),
            }
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        if let Some(w) = &mut self.work {
            w.destroy(ctx);
        }
        self.kernel.destroy(ctx);
        unsafe {
            ctx.device.destroy_pipeline_layout(self.layout, None);
            ctx.device.destroy_sampler(self.sampler, None);
        }
        self.set.destroy(ctx);
    }
}
