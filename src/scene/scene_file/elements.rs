//! Conversion of single definitions: lights, materials, object transforms,
//! procedural primitives, and the HDR environment map.

use std::path::Path;

use anyhow::{bail, ensure, Context, Result};
use glam::{DVec3, EulerRot, Quat, Vec3};

use super::checks::{finite3, finite3_f64, non_negative, non_negative3, unit, unit_interval};
use super::schema::{Cells, LightDef, LightType, MaterialDef, ObjectDef, PrimitiveKind, Scalar3, Size};
use crate::scene::{
    primitives, AlphaMode, Clearcoat, HdrImage, Light, LightKind, Material, Primitive, Transform,
};

pub(super) fn light_from_def(l: LightDef, kind: LightType, name: String) -> Result<Light> {
    let color = non_negative3(l.color.unwrap_or([1.0; 3]), "color")?;
    let intensity = non_negative(l.intensity.unwrap_or(1.0), "intensity")?;
    let position = l.position.map(|p| finite3_f64(p, "position")).transpose()?;
    let aim = match (l.direction, l.target) {
        (Some(_), Some(_)) => bail!("set either `direction` or `target`, not both"),
        (Some(d), None) => Some(unit(d, "direction")?),
        (None, Some(t)) => {
            let from = position.context("`target` needs a `position`")?;
            Some(unit((finite3_f64(t, "target")? - from).as_vec3().to_array(), "target - position")?)
        }
        (None, None) => None,
    };
    if let Some(r) = l.range {
        ensure!(r > 0.0 && r.is_finite(), "range must be positive");
    }
    let has_cones = l.inner_cone_deg.is_some() || l.outer_cone_deg.is_some();
    ensure!(kind == LightType::Spot || !has_cones, "cone angles only apply to spot lights");
    let (kind, position, direction) = match kind {
        LightType::Directional => {
            ensure!(position.is_none(), "a directional light has no position");
            (LightKind::Directional, DVec3::ZERO, aim.context("a directional light needs `direction`")?)
        }
        LightType::Point => {
            ensure!(aim.is_none(), "a point light has no direction");
            (LightKind::Point, position.context("a point light needs `position`")?, Vec3::NEG_Y)
        }
        LightType::Spot => {
            // KHR_lights_punctual defaults: inner 0, outer 45 degrees.
            let inner = l.inner_cone_deg.unwrap_or(0.0);
            let outer = l.outer_cone_deg.unwrap_or(45.0);
            ensure!(
                (0.0..outer).contains(&inner) && outer <= 90.0,
                "cone angles need 0 <= inner_cone_deg < outer_cone_deg <= 90"
            );
            let kind = LightKind::Spot { inner_cone: inner.to_radians(), outer_cone: outer.to_radians() };
            let position = position.context("a spot light needs `position`")?;
            (kind, position, aim.context("a spot light needs `direction` or `target`")?)
        }
    };
    Ok(Light {
        name,
        kind,
        color,
        intensity,
        position,
        direction,
        range: l.range,
        casts_shadows: l.casts_shadows.unwrap_or(true),
        node: None,
    })
}

pub(super) fn material_from_def(m: MaterialDef) -> Result<Material> {
    let mut base_color = [1.0; 4];
    if let Some(c) = &m.base_color {
        ensure!(c.len() == 3 || c.len() == 4, "base_color needs 3 or 4 components, got {}", c.len());
        ensure!(m.opacity.is_none() || c.len() == 3, "set the alpha either in base_color or as opacity");
        for (dst, &v) in base_color.iter_mut().zip(c) {
            *dst = non_negative(v, "base_color")?;
        }
    }
    if let Some(o) = m.opacity {
        base_color[3] = o;
    }
    ensure!(base_color[3] <= 1.0, "opacity must be within [0, 1]");
    let emissive = non_negative3(m.emissive.unwrap_or([0.0; 3]), "emissive")?;
    let strength = non_negative(m.emissive_strength.unwrap_or(1.0), "emissive_strength")?;
    let ior = m.ior.unwrap_or(1.5);
    ensure!(ior >= 1.0 && ior.is_finite(), "ior must be at least 1");
    let attenuation_color = m.attenuation_color.unwrap_or([1.0; 3]);
    for c in attenuation_color {
        unit_interval(c, "attenuation_color")?;
    }
    let attenuation_distance = m.attenuation_distance.unwrap_or(f32::INFINITY);
    ensure!(
        attenuation_distance > 0.0 && !attenuation_distance.is_nan(),
        "attenuation_distance must be above 0 (a length in world units; leave it out for a clear medium)"
    );
    Ok(Material {
        name: m.name.get_ref().clone(),
        base_color,
        metallic: unit_interval(m.metallic.unwrap_or(0.0), "metallic")?,
        roughness: unit_interval(m.roughness.unwrap_or(0.5), "roughness")?,
        emissive: (emissive * strength).to_array(),
        alpha_mode: if base_color[3] < 1.0 { AlphaMode::Blend } else { AlphaMode::Opaque },
        double_sided: m.double_sided.unwrap_or(false),
        transmission: unit_interval(m.transmission.unwrap_or(0.0), "transmission")?,
        ior,
        specular: unit_interval(m.specular.unwrap_or(1.0), "specular")?,
        specular_color: non_negative3(m.specular_color.unwrap_or([1.0; 3]), "specular_color")?.to_array(),
        clearcoat: Clearcoat {
            factor: unit_interval(m.clearcoat.unwrap_or(0.0), "clearcoat")?,
            roughness: unit_interval(m.clearcoat_roughness.unwrap_or(0.0), "clearcoat_roughness")?,
            ..Clearcoat::default()
        },
        attenuation_color,
        attenuation_distance,
        casts_shadows: m.casts_shadows.unwrap_or(true),
        ..Material::default()
    })
}

/// Translation, then rotation (X, then Y, then Z about the world axes, as
/// Blender's "XYZ Euler"), then scale: the usual TRS.
pub(super) fn object_transform(o: &ObjectDef) -> Result<Transform> {
    let translation = finite3_f64(o.translation.unwrap_or([0.0; 3]), "translation")?;
    let [x, y, z] =
        finite3(o.rotation_deg.unwrap_or([0.0; 3]), "rotation_deg")?.to_array().map(f32::to_radians);
    let scale = match o.scale.unwrap_or(Scalar3::Uniform(1.0)) {
        Scalar3::Uniform(s) => Vec3::splat(s),
        Scalar3::PerAxis(s) => Vec3::from(s),
    };
    ensure!(scale.is_finite() && scale.cmpne(Vec3::ZERO).all(), "scale must be finite and non-zero");
    Ok(Transform { translation, rotation: Quat::from_euler(EulerRot::ZYX, z, y, x), scale })
}

pub(super) fn check_no_shape_parameters(o: &ObjectDef, what: &str) -> Result<()> {
    let set = [
        ("size", o.size.is_some()),
        ("radius", o.radius.is_some()),
        ("slices", o.slices.is_some()),
        ("stacks", o.stacks.is_some()),
        ("cells", o.cells.is_some()),
        ("height", o.height.is_some()),
    ];
    if let Some((key, _)) = set.iter().find(|(_, s)| *s) {
        bail!("`{key}` only applies to primitives; scale {what} with `scale`");
    }
    Ok(())
}

pub(super) fn procedural(o: &ObjectDef, kind: PrimitiveKind) -> Result<Primitive> {
    let sphere_only = o.radius.is_some() || o.slices.is_some() || o.stacks.is_some();
    ensure!(
        kind == PrimitiveKind::Sphere || !sphere_only,
        "`radius`, `slices` and `stacks` only apply to spheres"
    );
    ensure!(
        kind == PrimitiveKind::Terrain || (o.cells.is_none() && o.height.is_none()),
        "`cells` and `height` only apply to terrains"
    );
    let positive = |v: f32, what: &str| {
        ensure!(v > 0.0 && v.is_finite(), "{what} must be positive");
        Ok(v)
    };
    Ok(match kind {
        PrimitiveKind::Plane => {
            let [x, z] = size_xz(o, 10.0);
            primitives::plane(positive(x, "size")?, positive(z, "size")?)
        }
        PrimitiveKind::Cube => match o.size.unwrap_or(Size::Uniform(1.0)) {
            Size::Uniform(s) => primitives::cube(positive(s, "size")?),
            Size::Xz(_) => bail!("a cube's `size` is one number (use `scale` for boxes)"),
        },
        PrimitiveKind::Sphere => {
            ensure!(o.size.is_none(), "a sphere takes `radius`, not `size`");
            let (slices, stacks) = (o.slices.unwrap_or(64), o.stacks.unwrap_or(32));
            ensure!(slices >= 3 && stacks >= 2, "a sphere needs slices >= 3 and stacks >= 2");
            // Bounds the vertex allocation (slices * stacks) for any input.
            ensure!(
                slices <= 4096 && stacks <= 4096,
                "a sphere allows at most 4096 slices and 4096 stacks (got {slices} and {stacks})"
            );
            primitives::uv_sphere(positive(o.radius.unwrap_or(0.5), "radius")?, slices, stacks)
        }
        PrimitiveKind::Terrain => {
            let [x, z] = size_xz(o, 100.0);
            let [cx, cz] = match o.cells.unwrap_or(Cells::Uniform(64)) {
                Cells::Uniform(c) => [c, c],
                Cells::Xz(c) => c,
            };
            let max = primitives::TERRAIN_MAX_CELLS;
            ensure!(
                (1..=max).contains(&cx) && (1..=max).contains(&cz),
                "a terrain has 1 to {max} cells per side (got {cx} x {cz})"
            );
            let height = o.height.unwrap_or(0.1 * x.max(z));
            ensure!(height >= 0.0 && height.is_finite(), "height must be finite and >= 0");
            primitives::terrain(positive(x, "size")?, positive(z, "size")?, cx, cz, height)
        }
    })
}

/// A plane's or terrain's `size`: one number for a square, `default` when unset.
fn size_xz(o: &ObjectDef, default: f32) -> [f32; 2] {
    match o.size.unwrap_or(Size::Uniform(default)) {
        Size::Uniform(s) => [s, s],
        Size::Xz(xz) => xz,
    }
}

/// A Radiance HDR environment map in `layout`, as equirect (an angular
/// probe is converted, `env_layout`).
pub fn load_env_map(path: &Path, layout: crate::scene::EnvLayout) -> Result<HdrImage> {
    let map = load_hdr(path)?;
    match layout {
        crate::scene::EnvLayout::Equirect => Ok(map),
        crate::scene::EnvLayout::Angular => crate::scene::env_layout::angular_to_equirect(&map, path),
    }
}

/// Equirectangular Radiance HDR; non-finite and negative texels (which would
/// poison importance sampling) become 0.
pub fn load_hdr(path: &Path) -> Result<HdrImage> {
    let image =
        image::open(path).with_context(|| format!("cannot load environment map '{}'", path.display()))?;
    if !matches!(image.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F) {
        // An 8- or 16-bit image holds display values clipped at white, not
        // radiance: the sky's brightest texels (the sun) are lost.
        log::warn!(
            "environment map '{}' is a {:?} image, not HDR: its values are read as linear radiance in [0, 1], \
             clipped at white (use a Radiance .hdr or OpenEXR map for image-based lighting)",
            path.display(),
            image.color()
        );
    }
    let image = image.into_rgb32f();
    let (width, height) = image.dimensions();
    let mut rgb = image.into_raw();
    let mut bad = 0usize;
    for v in &mut rgb {
        if !v.is_finite() || *v < 0.0 {
            *v = 0.0;
            bad += 1;
        }
    }
    if bad > 0 {
        log::warn!("{}: {bad} non-finite or negative values set to 0", path.display());
    }
    Ok(HdrImage { width, height, rgb })
}
