//! Node animations (translation, rotation, scale channels) and skins
//! (joints, inverse bind matrices, joint indices checked against them).

use std::path::Path;

use anyhow::{bail, ensure, Context, Result};
use glam::{Mat4, Quat, Vec3};
use gltf::accessor::{DataType, Dimensions};

use super::checks::{check_accessor, Expected};
use super::values::{sane, HUGE};
use crate::scene::animation::{Animation, AnimationChannel, Channel, Interpolation};
use crate::scene::skin::{Skin, SkinWeights};
use crate::scene::Scene;

const ANIMATION_INPUT: Expected =
    Expected { what: "animation input", dims: Dimensions::Scalar, types: &[DataType::F32], normalized: true };
const ANIMATION_VEC3: Expected =
    Expected { what: "animation output", dims: Dimensions::Vec3, types: &[DataType::F32], normalized: true };
const ANIMATION_ROTATION: Expected = Expected {
    what: "animation output",
    dims: Dimensions::Vec4,
    types: &[DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16],
    normalized: true,
};

/// Node animations; glTF node indices are the scene's node indices. Morph
/// target (`weights`) channels are skipped with a warning.
pub(super) fn convert_animations(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    path: &Path,
) -> Result<Vec<Animation>> {
    let mut animations = Vec::new();
    for anim in doc.animations() {
        let name = anim.name().map_or_else(|| format!("animation {}", anim.index()), str::to_string);
        let mut channels = Vec::new();
        for channel in anim.channels() {
            let context = || format!("animation '{name}' channel {}", channel.index());
            if channel.target().property() == gltf::animation::Property::MorphTargetWeights {
                log::warn!(
                    "{}: {}: morph target weights are not supported, channel skipped",
                    path.display(),
                    context()
                );
                continue;
            }
            channels.push(convert_channel(&channel, buffers).with_context(context)?);
        }
        animations.push(Animation::new(name, channels));
    }
    Ok(animations)
}

fn convert_channel(channel: &gltf::animation::Channel, buffers: &[Vec<u8>]) -> Result<AnimationChannel> {
    use gltf::animation::util::ReadOutputs;
    let sampler = channel.sampler();
    let interpolation = match sampler.interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let (input, output) = (sampler.input(), sampler.output());
    check_accessor(&input, &ANIMATION_INPUT, buffers)?;
    let rotation = channel.target().property() == gltf::animation::Property::Rotation;
    check_accessor(&output, if rotation { &ANIMATION_ROTATION } else { &ANIMATION_VEC3 }, buffers)?;
    ensure!(
        output.data_type() == DataType::F32 || output.normalized(),
        "animation output accessor {}: integer rotations must be normalized",
        output.index()
    );
    let reader = channel.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let times: Vec<f32> = reader.read_inputs().context("cannot read the animation input")?.collect();
    ensure!(
        times.len() == input.count(),
        "animation input: read {} of {} key times",
        times.len(),
        input.count()
    );
    let values = match reader.read_outputs().context("cannot read the animation output")? {
        ReadOutputs::Translations(it) => Channel::Translation(it.map(Vec3::from).collect()),
        ReadOutputs::Scales(it) => Channel::Scale(it.map(Vec3::from).collect()),
        ReadOutputs::Rotations(it) => Channel::Rotation(it.into_f32().map(Quat::from_array).collect()),
        ReadOutputs::MorphTargetWeights(_) => bail!("morph target weights are not supported"),
    };
    ensure!(
        values.len() == output.count(),
        "animation output: read {} of {} values",
        values.len(),
        output.count()
    );
    // Huge values overflow f32 once composed with the hierarchy.
    let bad = match &values {
        Channel::Translation(v) | Channel::Scale(v) => {
            v.iter().position(|v| !v.to_array().into_iter().all(sane))
        }
        Channel::Rotation(v) => v.iter().position(|q| !q.to_array().into_iter().all(sane)),
    };
    if let Some(i) = bad {
        bail!("animation output accessor {}: value {i} is not finite or is 1e30 or more", output.index());
    }
    if let Some(i) = times.iter().position(|t| t.is_finite() && t.abs() >= HUGE) {
        bail!("animation input accessor {}: key time {i} ({}) is 1e30 or more", input.index(), times[i]);
    }
    let channel = AnimationChannel { node: channel.target().node().index(), times, interpolation, values };
    channel.check()?;
    Ok(channel)
}

/// glTF skins, and the joint indices of every skinned node's mesh checked
/// against its skin (an out-of-range joint would read past the joint
/// matrices on the GPU).
pub(super) fn convert_skins(doc: &gltf::Document, buffers: &[Vec<u8>], scene: &mut Scene) -> Result<()> {
    for skin in doc.skins() {
        let name = skin.name().map_or_else(|| format!("skin {}", skin.index()), str::to_string);
        let context = || format!("skin '{name}'");
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        ensure!(!joints.is_empty(), "{}: has no joints", context());
        let inverse_bind = match skin.inverse_bind_matrices() {
            Some(acc) => {
                const IBM: Expected = Expected {
                    what: "inverseBindMatrices",
                    dims: Dimensions::Mat4,
                    types: &[DataType::F32],
                    normalized: true,
                };
                check_accessor(&acc, &IBM, buffers).with_context(context)?;
                ensure!(
                    acc.count() >= joints.len(),
                    "{}: {} inverse bind matrices for {} joints",
                    context(),
                    acc.count(),
                    joints.len()
                );
                let reader = skin.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
                let m: Vec<Mat4> = reader
                    .read_inverse_bind_matrices()
                    .with_context(|| format!("{}: cannot read inverseBindMatrices", context()))?
                    .map(|m| Mat4::from_cols_array_2d(&m))
                    .collect();
                ensure!(m.iter().all(|m| m.is_finite()), "{}: non-finite inverse bind matrix", context());
                m
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        scene.skins.push(Skin { name, joints, inverse_bind });
    }
    for node in doc.nodes() {
        let (Some(skin), Some(mesh)) = (node.skin(), node.mesh()) else { continue };
        let n = node.index();
        scene.nodes[n].skin = Some(skin.index());
        let s = &scene.skins[skin.index()];
        let m = &scene.meshes[mesh.index()];
        for (p, prim) in m.primitives.iter().enumerate() {
            let Some(max) = prim.skin.as_ref().and_then(SkinWeights::max_joint) else { continue };
            ensure!(
                (max as usize) < s.joints.len(),
                "node '{}': mesh '{}' primitive {p} uses joint {max} but skin '{}' has {} joints",
                scene.nodes[n].name,
                m.name,
                s.name,
                s.joints.len()
            );
        }
    }
    Ok(())
}
