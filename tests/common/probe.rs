//! Runs glsl/probes/shading.comp: the renderer's own compiled shading
//! functions evaluated on given inputs, for closed-form tests.
#![allow(dead_code)]

use ash::vk;
use gpu_allocator::MemoryLocation;
use hybrid_rt::gpu::shared;
use hybrid_rt::vk::memory::Buffer;
use hybrid_rt::vk::pipeline::{
    bind_compute, compute_pipeline, pipeline_layout, DescriptorSet, Specialization,
};

/// One input of the probe (the shader's `ProbeCase`, scalar layout).
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Case {
    pub op: u32,
    pub a: f32,
    pub b: f32,
    pub c: f32,
    pub p: [f32; 4],
    pub q: [f32; 4],
    pub r: [f32; 4],
}

impl Case {
    pub fn fresnel(cos_i: f32, eta: f32) -> Case {
        Case { op: shared::PROBE_FRESNEL, a: cos_i, b: eta, ..Default::default() }
    }
    pub fn schlick(f0: f32, cos: f32) -> Case {
        Case { op: shared::PROBE_SCHLICK, a: cos, p: [f0, f0, f0, 0.0], ..Default::default() }
    }
    /// brdf_eval on a surface with normal +Z: base colour, metallic,
    /// roughness, transmission, ior; view `v`, light `l` (unit).
    #[allow(clippy::too_many_arguments)]
    pub fn brdf(
        base: f32,
        metallic: f32,
        roughness: f32,
        transmission: f32,
        ior: f32,
        v: [f32; 3],
        l: [f32; 3],
    ) -> Case {
        Case {
            op: shared::PROBE_BRDF,
            a: metallic,
            b: roughness,
            c: transmission,
            p: [base, base, base, ior],
            q: [v[0], v[1], v[2], 0.0],
            r: [l[0], l[1], l[2], 0.0],
        }
    }
    /// GGX D(n.h) and the height-correlated Smith V(n.v, n.l) for alpha².
    pub fn ggx(n_h: f32, a2: f32, n_v: f32, n_l: f32) -> Case {
        Case { op: shared::PROBE_GGX, a: n_h, b: a2, p: [n_v, n_l, 0.0, 0.0], ..Default::default() }
    }
    /// offset_ray(p, n, extent): `extent` is the largest |coordinate| of the
    /// triangle `p` lies on.
    pub fn offset(p: [f32; 3], n: [f32; 3], extent: f32) -> Case {
        Case {
            op: shared::PROBE_OFFSET,
            p: [p[0], p[1], p[2], extent],
            q: [n[0], n[1], n[2], 0.0],
            ..Default::default()
        }
    }
    /// Tone curve `op` (TONEMAP_*) on an exposed colour, white point `white`.
    pub fn tonemap(op: u32, c: [f32; 3], white: f32) -> Case {
        Case {
            op: shared::PROBE_TONEMAP,
            b: op as f32,
            c: white,
            p: [c[0], c[1], c[2], 0.0],
            ..Default::default()
        }
    }
    /// `steps` adaptation steps of `dt` from `adapted` towards `target`:
    /// x log-average, y histogram at (brighten, darken) EV/s.
    pub fn adapt(adapted: f32, target: f32, dt: f32, steps: u32, speeds: [f32; 2]) -> Case {
        Case {
            op: shared::PROBE_ADAPT,
            a: adapted,
            b: target,
            c: dt,
            p: [speeds[0], speeds[1], steps as f32, 0.0],
            ..Default::default()
        }
    }
    pub fn refract(i: [f32; 3], n: [f32; 3], eta: f32) -> Case {
        Case {
            op: shared::PROBE_REFRACT,
            a: eta,
            p: [i[0], i[1], i[2], 0.0],
            q: [n[0], n[1], n[2], 0.0],
            ..Default::default()
        }
    }
    /// The G-buffer normal's octahedral encode + decode of `n`.
    pub fn octahedral(n: [f32; 3]) -> Case {
        Case { op: shared::PROBE_OCTAHEDRAL, p: [n[0], n[1], n[2], 0.0], ..Default::default() }
    }
}

/// Evaluates every case on the GPU (validated context); one vec4 per case.
pub fn run(cases: &[Case]) -> Vec<[f32; 4]> {
    assert!(!cases.is_empty());
    let ctx = super::validated_context();
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let mut input = Buffer::new(
        &ctx,
        "probe cases",
        std::mem::size_of_val(cases) as u64,
        usage,
        MemoryLocation::CpuToGpu,
    )
    .unwrap();
    input.write(0, bytemuck::cast_slice(cases)).unwrap();
    let mut output =
        Buffer::new(&ctx, "probe results", (cases.len() * 16) as u64, usage, MemoryLocation::GpuToCpu)
            .unwrap();
    let mut set = DescriptorSet::storage_buffers(
        &ctx,
        "probe",
        &[(shared::PROBE_IN, input.raw), (shared::PROBE_OUT, output.raw)],
    )
    .unwrap();
    let layout = pipeline_layout(&ctx, "probe", &[set.layout], 4).unwrap();
    let pipeline = compute_pipeline(&ctx, "probes/shading.comp", layout, &Specialization::new(&[])).unwrap();
    let count = cases.len() as u32;
    ctx.one_shot("probe", |cmd| {
        bind_compute(&ctx, cmd, pipeline, layout, &[set.set]);
        unsafe {
            ctx.device.cmd_push_constants(cmd, layout, vk::ShaderStageFlags::ALL, 0, &count.to_ne_bytes());
            ctx.device.cmd_dispatch(cmd, count.div_ceil(64), 1, 1);
        }
        hybrid_rt::vk::memory_barrier(
            &ctx,
            cmd,
            (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
            (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
        );
        Ok(())
    })
    .unwrap();
    let results: Vec<[f32; 4]> = bytemuck::cast_slice(output.read().unwrap()).to_vec();
    unsafe {
        ctx.device.destroy_pipeline(pipeline, None);
        ctx.device.destroy_pipeline_layout(layout, None);
    }
    set.destroy(&ctx);
    input.destroy(&ctx);
    output.destroy(&ctx);
    results[..cases.len()].to_vec()
}
