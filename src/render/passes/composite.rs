//! Pass `composite`: emission + direct light + ambient environment light (scaled by the traced
//! visibility where `ao filter` runs) + the specular chain at the primary hit, the environment where the camera
//! ray missed (glsl/composite.comp); or, in a debug view, the G-buffer view.

use ash::vk;

use super::fullscreen::{self, FullScreen, Shader, TargetBinding};
use super::{
    ao_filter, direct, gbuffer, glossy_filter, reference, specular, terms, Creation, PassDesc, Upstream,
};
use crate::gpu::shared::{
    AO_EMITTER_SPECULAR_IN, AO_VISIBILITY_IN, DIRECT_IN, HDR_OUT, REFERENCE_IN, SPECULAR_IN, TERMS_IN,
};
use crate::render::frame::{Access, SharedBuffer, Use};
use crate::render::shading::ShadingConfig;
use crate::render::targets::TargetDesc;
use crate::vk::pipeline::Specialization;

/// Linear radiance of the frame.
pub static HDR: TargetDesc = TargetDesc::new("hdr radiance", vk::Format::R32G32B32A32_SFLOAT);

/// The optional inputs, as handles from the passes before: each is there
/// when a pass of this frame writes it.
struct Inputs {
    specular: Option<&'static TargetDesc>,
    reference: Option<&'static TargetDesc>,
    terms: Option<&'static TargetDesc>,
    visibility: Option<&'static TargetDesc>,
    emitter_specular: Option<&'static TargetDesc>,
}

impl Inputs {
    fn of(up: &Upstream) -> Inputs {
        Inputs {
            // The glossy filter's output carries the specular chain too.
            specular: up.get(&glossy_filter::REFLECTED).or(up.get(&specular::SPECULAR)),
            reference: up.get(&reference::ACCUMULATION),
            terms: up.get(&terms::ACCUMULATION),
            visibility: up.get(&ao_filter::VISIBILITY),
            emitter_specular: up.get(&ao_filter::EMITTER_SPECULAR),
        }
    }
}

fn io(c: &ShadingConfig, inputs: &Inputs) -> Vec<TargetBinding> {
    let mut io = gbuffer::reads();
    if !c.debug_view {
        io.push(TargetBinding::new(DIRECT_IN, &direct::DIRECT, Access::StorageRead));
    }
    for (binding, input) in [
        (SPECULAR_IN, inputs.specular),
        (REFERENCE_IN, inputs.reference),
        (TERMS_IN, inputs.terms),
        (AO_VISIBILITY_IN, inputs.visibility),
        (AO_EMITTER_SPECULAR_IN, inputs.emitter_specular),
    ] {
        if let Some(t) = input {
            io.push(TargetBinding::new(binding, t, Access::StorageRead));
        }
    }
    io.push(TargetBinding::new(HDR_OUT, &HDR, Access::StorageWrite));
    io
}

/// The shader variant that reads exactly the inputs there are.
fn shader(c: &ShadingConfig, inputs: &Inputs) -> &'static str {
    if inputs.emitter_specular.is_some() {
        // (Only beside the visibility.)
        return match (inputs.specular.is_some(), inputs.terms.is_some()) {
            (true, true) => "composite_specular_terms_ao_emitters",
            (true, false) => "composite_specular_ao_emitters",
            (false, true) => "composite_terms_ao_emitters",
            (false, false) => "composite_ao_emitters",
        };
    }
    // (ShadingConfig::resolve allows terms neither beside the reference
    // nor in a debug view, and the visibility not beside the reference.)
    let (specular, reference, terms, ao) = (
        inputs.specular.is_some(),
        inputs.reference.is_some(),
        inputs.terms.is_some(),
        inputs.visibility.is_some(),
    );
    match (c.debug_view, specular, reference, terms, ao) {
        (true, ..) => "composite_debug",
        (false, true, true, ..) => "composite_specular_reference",
        (false, true, false, true, true) => "composite_specular_terms_ao",
        (false, true, false, true, false) => "composite_specular_terms",
        (false, true, false, false, true) => "composite_specular_ao",
        (false, true, false, false, false) => "composite_specular",
        (false, false, true, ..) => "composite_reference",
        (false, false, false, true, true) => "composite_terms_ao",
        (false, false, false, true, false) => "composite_terms",
        (false, false, false, false, true) => "composite_ao",
        (false, false, false, false, false) => "composite.comp",
    }
}

pub const PASS: PassDesc = PassDesc {
    name: "composite",
    this_frame: super::every_frame,
    skip: |_| None,
    uses: |c, up| {
        // Emission is looked up from the triangle's material, so this reads the scene geometry, which
        // skinning may have just written.
        let mut u = fullscreen::uses(&io(c, &Inputs::of(up)), false);
        u.push(Use::buffer(SharedBuffer::Geometry, Access::ShaderRead));
        u
    },
    create: |i: &Creation| {
        let spec = Specialization::new(&i.config.specialization());
        let inputs = Inputs::of(i.upstream);
        FullScreen::create(
            i,
            "composite",
            io(i.config, &inputs),
            Shader::Compute(shader(i.config, &inputs)),
            &spec,
        )
    },
};
