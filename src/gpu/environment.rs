//! The environment map on the GPU: its texels as RGBA16F (RGBA32F where
//! a texel exceeds half's range and the device filters it), its mean
//! radiance and the SH projection of what the shaders sample.

use anyhow::Result;
use ash::vk;
use glam::Vec3;

use super::env_prefilter::{prefilter, Prefiltered, SAMPLES};
use super::env_sh::project_environment;
use crate::scene::sh::ShCoeffs;
use crate::scene::{HdrImage, Scene};
use crate::vk::{Context, Image};

/// What the shaders read of the environment (set 0).
pub(super) struct UploadedEnvironment {
    pub map: Image,
    /// The GGX-prefiltered chain (gpu/env_prefilter.rs); 1x1 black without a map.
    pub specular: Image,
    pub mean: Vec3,
    pub sh: Option<ShCoeffs>,
}

/// Uploads the equirectangular map and its prefiltered chain; returns them with the map's mean radiance
/// and SH projection (None without a map). Texels beyond half's range (a 1e5 sun, RGBE up to ~1.7e38)
/// go up as RGBA32F where the device filters it, so misses and the mean agree; else they are clamped to
/// 65504 with a warning, the mean taken after clamping. Without a map 1x1 black textures keep the
/// descriptors valid.
pub(super) fn upload_environment(ctx: &Context, scene: &Scene) -> Result<UploadedEnvironment> {
    let env = &scene.environment;
    let Some(map) = &env.map else {
        let black = |name| {
            let extent = vk::Extent2D { width: 1, height: 1 };
            Image::texture(ctx, name, vk::Format::R16G16B16A16_SFLOAT, extent, &[0u8; 8], false)
        };
        let mut map = black("environment (none)")?;
        let specular = match black("environment specular (none)") {
            Ok(s) => s,
            Err(e) => {
                map.destroy(ctx);
                return Err(e);
            }
        };
        return Ok(UploadedEnvironment { map, specular, mean: env.color * env.intensity, sh: None });
    };
    let sanitized = |v: f32| if v.is_finite() { v.max(0.0) } else { 0.0 };
    let over_half = map.rgb.iter().filter(|v| sanitized(**v) > HALF_MAX).count();
    let wide = over_half > 0 && filters_linearly(ctx, vk::Format::R32G32B32A32_SFLOAT);
    if over_half > 0 && !wide {
        log::warn!(
            "environment map: {over_half} channel values above 65504 clamped (this device cannot filter RGBA32F)"
        );
    }
    let format = if wide { vk::Format::R32G32B32A32_SFLOAT } else { vk::Format::R16G16B16A16_SFLOAT };
    // What the shaders sample: sanitized, clamped to half's range unless wide.
    let stored = |v: f32| if wide { sanitized(v) } else { sanitized(v).min(HALF_MAX) };
    let changed = map.rgb.iter().any(|v| stored(*v) != *v);
    let copy;
    let sampled = if changed {
        copy = HdrImage {
            width: map.width,
            height: map.height,
            rgb: map.rgb.iter().map(|v| stored(*v)).collect(),
        };
        &copy
    } else {
        map
    };
    let texels_of =
        |img: &HdrImage| img.rgb.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>();
    let texels = texels_of(sampled);
    let mean = equirect_mean(texels.iter().copied(), map.width, map.height) * env.intensity;
    let sh = project_environment(sampled)?;
    let t0 = std::time::Instant::now();
    let Prefiltered { levels, hot_texels } = prefilter(sampled, SAMPLES)?;
    log::info!(
        "environment specular: GGX-prefiltered {} levels from {}x{} ({} lobe samples a texel at level 1, \
         doubling per level; {hot_texels} hot texels summed exactly), {:.0} ms",
        levels.len(),
        levels[0].width,
        levels[0].height,
        SAMPLES,
        t0.elapsed().as_secs_f64() * 1e3
    );
    let mut img = Image::texture(
        ctx,
        "environment map",
        format,
        vk::Extent2D { width: map.width, height: map.height },
        &rgba_bytes(texels, wide),
        false,
    )?;
    let extent = vk::Extent2D { width: levels[0].width, height: levels[0].height };
    let bytes: Vec<Vec<u8>> = levels.iter().map(|l| rgba_bytes(texels_of(l), wide)).collect();
    match Image::texture_levels(ctx, "environment specular", format, extent, &bytes) {
        Ok(specular) => Ok(UploadedEnvironment { map: img, specular, mean, sh: Some(sh) }),
        Err(e) => {
            img.destroy(ctx);
            Err(e)
        }
    }
}

/// RGBA texels, as f32 (`wide`) or half.
fn rgba_bytes(texels: Vec<Vec3>, wide: bool) -> Vec<u8> {
    let mut out = Vec::with_capacity(texels.len() * if wide { 16 } else { 8 });
    for c in texels {
        for v in [c.x, c.y, c.z, 1.0] {
            if wide {
                out.extend_from_slice(&v.to_le_bytes());
            } else {
                out.extend_from_slice(&f32_to_f16(v).to_le_bytes());
            }
        }
    }
    out
}

/// The largest finite half float.
pub const HALF_MAX: f32 = 65504.0;

fn filters_linearly(ctx: &Context, format: vk::Format) -> bool {
    let props =
        unsafe { ctx.instance.raw.get_physical_device_format_properties(ctx.physical_device, format) };
    props.optimal_tiling_features.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR)
}

/// Solid-angle weighted mean (row weight sin θ), summed in f64: near the RGBE maximum an f32 sum hit
/// Inf, which made the ambient NaN and the frame black. Clamped to the largest finite f32.
pub fn equirect_mean(texels: impl Iterator<Item = Vec3>, width: u32, height: u32) -> Vec3 {
    let mut sum = glam::DVec3::ZERO;
    let mut weight = 0.0f64;
    for (i, c) in texels.enumerate() {
        let y = i as u32 / width.max(1);
        let w = (std::f64::consts::PI * (y as f64 + 0.5) / height.max(1) as f64).sin();
        sum += c.as_dvec3() * w;
        weight += w;
    }
    (sum / weight.max(1e-12)).min(glam::DVec3::splat(f32::MAX as f64)).as_vec3()
}

/// IEEE half from f32: round to nearest, overflow clamps to the largest
/// finite half (a very bright texel must not become Inf), NaN becomes 0.
pub fn f32_to_f16(v: f32) -> u16 {
    if v.is_nan() {
        return 0;
    }
    let v = v.clamp(-65504.0, 65504.0);
    let bits = v.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let exp = ((bits >> 23) & 0xff) as i32 - 127 + 15;
    let mant = bits & 0x7f_ffff;
    if exp <= 0 {
        if exp < -10 {
            return sign;
        }
        let m = (mant | 0x80_0000) >> (1 - exp);
        return sign | ((m + 0x1000) >> 13) as u16;
    }
    let h = ((exp as u32) << 10) | (mant >> 13);
    let round = (mant >> 12) & 1;
    sign | (h + round).min(0x7bff) as u16
}

#[cfg(test)]
mod tests {
    use super::f32_to_f16;

    #[test]
    fn environment_mean_survives_texels_near_the_rgbe_maximum() {
        // Two rows of 2: one texel at 1.7e38 in every channel. An f32 sum
        // of sin-weighted texels overflows; the f64 one gives the mean.
        let big = glam::Vec3::splat(1.7e38);
        let texels = [big, glam::Vec3::ZERO, big, big];
        let m = super::equirect_mean(texels.into_iter(), 2, 2);
        assert!(m.is_finite(), "{m}");
        assert!((m.x / 1.7e38 - 0.75).abs() < 1e-6, "{m}");
        let ones = super::equirect_mean([glam::Vec3::ONE; 6].into_iter(), 3, 2);
        assert!((ones - glam::Vec3::ONE).abs().max_element() < 1e-6);
    }

    #[test]
    fn half_conversion() {
        assert_eq!(f32_to_f16(0.0), 0);
        assert_eq!(f32_to_f16(1.0), 0x3c00);
        assert_eq!(f32_to_f16(-2.0), 0xc000);
        assert_eq!(f32_to_f16(65504.0), 0x7bff);
        assert_eq!(f32_to_f16(1e9), 0x7bff);
        assert_eq!(f32_to_f16(f32::NAN), 0);
        assert_eq!(f32_to_f16(0.5), 0x3800);
        // Smallest normal half.
        assert_eq!(f32_to_f16(6.103_515_6e-5), 0x0400);
    }
}
