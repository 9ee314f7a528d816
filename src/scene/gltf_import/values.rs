//! Range checks of the numbers a glTF file gives materials, lights and
//! cameras, against the glTF 2.0 schema and the KHR extensions' specs.
//!
//! Policy: a value the spec does not allow is an error (never clamped), so a
//! file renders as its author meant or not at all. Finite values past 1e30
//! are errors too: their products (intensity * colour * BRDF) overflow f32.
//! Errors name the element; `load` adds the file.

use anyhow::{ensure, Result};

/// Magnitudes at or above this overflow f32 once multiplied a few times.
pub(super) const HUGE: f32 = 1e30;

/// `v` is finite and below [`HUGE`] in magnitude.
pub(super) fn sane(v: f32) -> bool {
    v.is_finite() && v.abs() < HUGE
}

/// `what` (e.g. "roughnessFactor") within `[lo, hi]`; `rule` is the spec's
/// wording for the message.
fn within(v: f32, lo: f32, hi: f32, what: &str, rule: &str) -> Result<()> {
    ensure!(sane(v) && (lo..=hi).contains(&v), "{what} {v} is out of range (glTF: {rule})");
    Ok(())
}

fn each_within(v: &[f32], lo: f32, hi: f32, what: &str, rule: &str) -> Result<()> {
    ensure!(
        v.iter().all(|&c| sane(c) && (lo..=hi).contains(&c)),
        "{what} {v:?} is out of range (glTF: {rule})"
    );
    Ok(())
}

/// Material factors; `context` names the material ("material 3 'glass'").
pub(super) fn check_material(m: &gltf::Material) -> Result<()> {
    let pbr = m.pbr_metallic_roughness();
    each_within(&pbr.base_color_factor(), 0.0, 1.0, "baseColorFactor", "each component in [0, 1]")?;
    within(pbr.metallic_factor(), 0.0, 1.0, "metallicFactor", "within [0, 1]")?;
    within(pbr.roughness_factor(), 0.0, 1.0, "roughnessFactor", "within [0, 1]")?;
    each_within(&m.emissive_factor(), 0.0, 1.0, "emissiveFactor", "each component in [0, 1]")?;
    if let Some(n) = m.normal_texture() {
        ensure!(sane(n.scale()), "normalTexture.scale {} must be finite", n.scale());
    }
    if let Some(o) = m.occlusion_texture() {
        within(o.strength(), 0.0, 1.0, "occlusionTexture.strength", "within [0, 1]")?;
    }
    if let Some(c) = m.alpha_cutoff() {
        within(c, 0.0, f32::MAX, "alphaCutoff", ">= 0")?;
    }
    if let Some(s) = m.emissive_strength() {
        within(s, 0.0, f32::MAX, "KHR_materials_emissive_strength emissiveStrength", ">= 0, finite")?;
    }
    if let Some(ior) = m.ior() {
        // The spec also allows 0 (a Fresnel term of 1, for the
        // specular-glossiness workflow); refraction here needs a real index.
        ensure!(
            sane(ior) && ior >= 1.0,
            "KHR_materials_ior ior {ior} is out of range (glTF: ior >= 1, or 0 meaning a Fresnel \
             term of 1, which this renderer does not support)"
        );
    }
    if let Some(s) = m.specular() {
        within(s.specular_factor(), 0.0, 1.0, "KHR_materials_specular specularFactor", "within [0, 1]")?;
        each_within(
            &s.specular_color_factor(),
            0.0,
            f32::MAX,
            "KHR_materials_specular specularColorFactor",
            "each component >= 0",
        )?;
    }
    if let Some(t) = m.transmission() {
        within(
            t.transmission_factor(),
            0.0,
            1.0,
            "KHR_materials_transmission transmissionFactor",
            "within [0, 1]",
        )?;
    }
    if let Some(v) = m.volume() {
        // Attenuation inside the mesh is rendered by the ray-traced
        // refraction chain and the path tracer; the thickness is not used.
        within(v.thickness_factor(), 0.0, f32::MAX, "KHR_materials_volume thicknessFactor", ">= 0")?;
        let d = v.attenuation_distance();
        // The default is +infinity ("no attenuation").
        ensure!(
            d > 0.0 && !d.is_nan() && (d == f32::INFINITY || d < HUGE),
            "KHR_materials_volume attenuationDistance {d} is out of range (glTF: > 0)"
        );
        each_within(
            &v.attenuation_color(),
            0.0,
            1.0,
            "KHR_materials_volume attenuationColor",
            "each component in [0, 1]",
        )?;
    }
    Ok(())
}

/// KHR_lights_punctual: colour in [0, 1], intensity >= 0, range > 0, spot
/// cones with 0 <= inner < outer <= pi / 2.
pub(super) fn check_light(light: &gltf::khr_lights_punctual::Light) -> Result<()> {
    use gltf::khr_lights_punctual::Kind;
    each_within(&light.color(), 0.0, 1.0, "color", "each component in [0, 1]")?;
    within(light.intensity(), 0.0, f32::MAX, "intensity", ">= 0, finite and below 1e30")?;
    if let Some(r) = light.range() {
        ensure!(sane(r) && r > 0.0, "range {r} is out of range (glTF: > 0)");
    }
    if let Kind::Spot { inner_cone_angle: inner, outer_cone_angle: outer } = light.kind() {
        let half_pi = std::f32::consts::FRAC_PI_2;
        within(inner, 0.0, half_pi, "spot.innerConeAngle", "within [0, pi/2]")?;
        within(outer, 0.0, half_pi, "spot.outerConeAngle", "within [0, pi/2]")?;
        ensure!(
            inner < outer,
            "spot.innerConeAngle {inner} must be smaller than spot.outerConeAngle {outer} (glTF)"
        );
    }
    Ok(())
}

/// Camera projections: perspective yfov > 0, znear > 0, zfar > znear,
/// aspectRatio > 0; orthographic xmag, ymag != 0, znear >= 0, zfar > znear.
pub(super) fn check_camera(cam: &gltf::Camera) -> Result<()> {
    let positive = |v: f32, what: &str| {
        ensure!(sane(v) && v > 0.0, "{what} {v} is out of range (glTF: finite and > 0)");
        Ok(())
    };
    match cam.projection() {
        gltf::camera::Projection::Perspective(p) => {
            positive(p.yfov(), "perspective.yfov")?;
            positive(p.znear(), "perspective.znear")?;
            if let Some(a) = p.aspect_ratio() {
                positive(a, "perspective.aspectRatio")?;
            }
            if let Some(far) = p.zfar() {
                ensure!(
                    sane(far) && far > p.znear(),
                    "perspective.zfar {far} is out of range (glTF: finite and > znear {})",
                    p.znear()
                );
            }
        }
        gltf::camera::Projection::Orthographic(o) => {
            for (v, what) in [(o.xmag(), "orthographic.xmag"), (o.ymag(), "orthographic.ymag")] {
                ensure!(sane(v) && v != 0.0, "{what} {v} is out of range (glTF: finite and not 0)");
            }
            within(o.znear(), 0.0, f32::MAX, "orthographic.znear", ">= 0")?;
            ensure!(
                sane(o.zfar()) && o.zfar() > o.znear(),
                "orthographic.zfar {} is out of range (glTF: finite and > znear {})",
                o.zfar(),
                o.znear()
            );
        }
    }
    Ok(())
}
