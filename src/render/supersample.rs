//! The supersampled reference (`--supersample K`): the frame rendered at K·W × K·H (K×K samples per pixel on
//! a regular grid, same camera) and filtered down to W × H on the CPU, to measure anti-aliasing against. The
//! large frame runs with `--aa none`, and its exposure is the compared frame's `RenderSettings` input
//! (frozen, never re-measured on the larger image), so both share one tone curve.

use anyhow::{Context as _, Result};
use ash::vk;

use super::shading::AaMode;
use super::srgb::{linear_to_srgb, srgb_to_linear};
use super::{FrameOutput, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
use crate::vk::Context;

/// How the K×K samples of a pixel are weighted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SampleFilter {
    /// The mean of the pixel's own K×K samples.
    #[default]
    Box,
    /// A Gaussian of sigma 0.5 pixels around the pixel centre, cut at 1.5
    /// pixels (3 sigma): also weighs in the neighbours' nearest samples,
    /// which a box filter's sharp cut-off aliases.
    Gaussian,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Supersample {
    /// Samples per pixel along each axis (K).
    pub factor: u32,
    pub filter: SampleFilter,
}

/// Largest K the command line accepts (16x16 = 256 samples per pixel).
pub const MAX_FACTOR: u32 = 16;

/// Samples the default anti-aliasing reference's large frame may hold (4096²: ~2 GB of targets).
const REFERENCE_SAMPLES: u64 = 1 << 24;

/// The default K of an anti-aliasing reference at `width` x `height`: 16 or 8 where the large frame stays
/// within REFERENCE_SAMPLES, else 4. Why not 4 everywhere: a K×K grid puts an edge's coverage on K + 1
/// levels per axis, and an analytic-coverage filter (`--aa edge`) measured *worse* than none against 4x4
/// on the default scene at 320x180 (ꟻLIP 0.0087 vs 0.0083) but better against 8x8 (0.0074 vs 0.0092)
/// and 16x16 (0.0070 vs 0.0084): the 4x4 grid, not the filter, was off.
pub fn reference_factor(width: u32, height: u32) -> u32 {
    let fits = |k: u64| width as u64 * height as u64 * k * k <= REFERENCE_SAMPLES;
    [MAX_FACTOR, 8].into_iter().find(|&k| fits(k as u64)).unwrap_or(4)
}

const GAUSSIAN_SIGMA: f64 = 0.5;
const GAUSSIAN_RADIUS: f64 = 1.5;

/// The large frame's size; an error naming `--supersample` when the device cannot allocate it.
pub fn large_extent(ctx: &Context, extent: vk::Extent2D, ss: &Supersample) -> Result<vk::Extent2D> {
    let k = ss.factor;
    let too_big = || {
        anyhow::anyhow!(
            "--supersample {k}: {}x{} x {k} is too large to render (maxImageDimension2D {})",
            extent.width,
            extent.height,
            ctx.caps.limits.max_image_dimension_2d
        )
    };
    let (w, h) =
        (extent.width.checked_mul(k).ok_or_else(too_big)?, extent.height.checked_mul(k).ok_or_else(too_big)?);
    ctx.caps
        .limits
        .check_extent(w, h)
        .with_context(|| format!("--supersample {k} at {}x{}", extent.width, extent.height))?;
    Ok(vk::Extent2D { width: w, height: h })
}

/// Renders `camera`'s view at `extent` supersampled by `ss` with its own
/// renderer (created for the large size and destroyed again).
pub fn render_supersampled(
    ctx: &Context,
    scene: &Scene,
    camera: &Camera,
    extent: vk::Extent2D,
    settings: &RenderSettings,
    ss: &Supersample,
) -> Result<FrameOutput> {
    let large = large_extent(ctx, extent, ss)?;
    log::info!(
        "supersampling {}x{} by {}x{} ({:?} filter): rendering {}x{}",
        extent.width,
        extent.height,
        ss.factor,
        ss.factor,
        ss.filter,
        large.width,
        large.height
    );
    let settings = RenderSettings { aa: AaMode::None, ..*settings };
    let mut renderer = Renderer::new(ctx, scene, large)?;
    let frame = renderer.render(ctx, scene, camera, &settings);
    renderer.destroy(ctx);
    Ok(downsample(&frame?, ss))
}

/// Filters a frame rendered at K·W × K·H down to W × H: the radiance as it is, the 8-bit image as linear
/// display values (decoded from sRGB, filtered, encoded and rounded), as a display blends sub-pixel
/// coverage. Timings and counters are the large frame's.
pub fn downsample(large: &FrameOutput, ss: &Supersample) -> FrameOutput {
    let k = ss.factor.max(1);
    let (w, h) = (large.width / k, large.height / k);
    let (tx, ty) = (taps(w, k, ss.filter), taps(h, k, ss.filter));
    let decode: Vec<f32> = (0..=255u8).map(|v| srgb_to_linear(v as f32 / 255.0)).collect();
    let ldr_linear: Vec<f32> = large.ldr.iter().map(|&v| decode[v as usize]).collect();
    let ldr = separable(&ldr_linear, large.width as usize, &tx, &ty)
        .into_iter()
        .map(|v| (linear_to_srgb(v) * 255.0 + 0.5).clamp(0.0, 255.0) as u8)
        .collect();
    let hdr = separable(&large.hdr, large.width as usize, &tx, &ty);
    FrameOutput {
        width: w,
        height: h,
        ldr,
        hdr,
        timings: large.timings.clone(),
        ray_counts: large.ray_counts,
        truncated_pixels: large.truncated_pixels,
        bad_pixels: large.bad_pixels,
        exposure: large.exposure,
        cold: large.cold,
    }
}

/// For each of `n` output pixels along one axis, its samples' indices and
/// normalized weights (`k` samples per pixel).
fn taps(n: u32, k: u32, filter: SampleFilter) -> Vec<Vec<(usize, f32)>> {
    let samples = (n * k) as i64;
    (0..n as i64)
        .map(|x| {
            let mut t: Vec<(usize, f64)> = match filter {
                SampleFilter::Box => (x * k as i64..(x + 1) * k as i64).map(|s| (s as usize, 1.0)).collect(),
                SampleFilter::Gaussian => (((x - 2) * k as i64).max(0)..((x + 3) * k as i64).min(samples))
                    .filter_map(|s| {
                        // Distance of the sample from the pixel centre, in pixels.
                        let r = ((s as f64 + 0.5) / k as f64 - (x as f64 + 0.5)).abs();
                        (r <= GAUSSIAN_RADIUS)
                            .then(|| (s as usize, (-r * r / (2.0 * GAUSSIAN_SIGMA * GAUSSIAN_SIGMA)).exp()))
                    })
                    .collect(),
            };
            // Renormalized: at the image border the Gaussian is cut.
            let sum: f64 = t.iter().map(|(_, w)| w).sum();
            t.iter_mut().for_each(|(_, w)| *w /= sum);
            t.into_iter().map(|(s, w)| (s, w as f32)).collect()
        })
        .collect()
}

/// RGBA `src` (rows of `width` pixels) filtered by `tx` along rows, then `ty` along columns.
fn separable(src: &[f32], width: usize, tx: &[Vec<(usize, f32)>], ty: &[Vec<(usize, f32)>]) -> Vec<f32> {
    let rows = src.len() / (4 * width);
    let w = tx.len();
    let mut horizontal = vec![0.0f32; rows * w * 4];
    for y in 0..rows {
        for (x, taps) in tx.iter().enumerate() {
            for &(s, wt) in taps {
                for c in 0..4 {
                    horizontal[(y * w + x) * 4 + c] += wt * src[(y * width + s) * 4 + c];
                }
            }
        }
    }
    let mut out = vec![0.0f32; ty.len() * w * 4];
    for (y, taps) in ty.iter().enumerate() {
        for &(s, wt) in taps {
            for x in 0..w * 4 {
                out[y * w * 4 + x] += wt * horizontal[s * w * 4 + x];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_reference_is_the_finest_grid_that_fits() {
        assert_eq!(reference_factor(64, 36), 16);
        assert_eq!(reference_factor(256, 256), 16);
        assert_eq!(reference_factor(320, 180), 16);
        assert_eq!(reference_factor(640, 360), 8);
        assert_eq!(reference_factor(512, 512), 8);
        assert_eq!(reference_factor(1280, 720), 4);
        assert_eq!(reference_factor(3840, 2160), 4, "never coarser than the old default");
    }

    fn frame(w: u32, h: u32, ldr: Vec<u8>, hdr: Vec<f32>) -> FrameOutput {
        FrameOutput::from_images(w, h, ldr, hdr)
    }

    #[test]
    fn box_filter_averages_each_pixels_samples_in_linear() {
        // 4x2 samples, K = 2: pixel 0 half black, half white; pixel 1 white.
        let px = |v: u8| [v, v, v, 255];
        let ldr: Vec<u8> = [0, 255, 255, 255, 0, 255, 255, 255].iter().flat_map(|&v| px(v)).collect();
        let hdr: Vec<f32> =
            [0.0, 2.0, 1.0, 1.0, 0.0, 2.0, 1.0, 1.0].iter().flat_map(|&v| [v, v, v, 1.0]).collect();
        let ss = Supersample { factor: 2, filter: SampleFilter::Box };
        let out = downsample(&frame(4, 2, ldr, hdr), &ss);
        assert_eq!((out.width, out.height), (2, 1));
        // Linear 0.5 is sRGB 188, not the 128 of averaging encoded values.
        assert_eq!(&out.ldr[..4], &[188, 188, 188, 255]);
        assert_eq!(&out.ldr[4..], &[255, 255, 255, 255]);
        assert_eq!(out.radiance(0, 0), [1.0; 3]);
        assert_eq!(out.radiance(1, 0), [1.0; 3]);
    }

    #[test]
    fn gaussian_weights_are_normalized_and_reach_the_neighbours() {
        for n in [1u32, 3, 7] {
            for k in [1u32, 2, 4] {
                for t in taps(n, k, SampleFilter::Gaussian) {
                    let sum: f32 = t.iter().map(|(_, w)| w).sum();
                    assert!((sum - 1.0).abs() < 1e-5, "n {n} k {k}: {sum}");
                }
            }
        }
        // An interior pixel at K = 4 uses its own 4 samples and the
        // neighbours' within 1.5 px: 12 in all, the nearest weighing most.
        let t = &taps(5, 4, SampleFilter::Gaussian)[2];
        assert_eq!(t.len(), 12, "{t:?}");
        let own: f32 = t.iter().filter(|(s, _)| (8..12).contains(s)).map(|(_, w)| w).sum();
        assert!(own > 0.5 && own < 1.0, "{own}");
        // A constant image stays constant.
        let hdr = vec![0.25f32; 8 * 8 * 4];
        let out = downsample(
            &frame(8, 8, vec![77; 8 * 8 * 4], hdr),
            &Supersample { factor: 4, filter: SampleFilter::Gaussian },
        );
        assert!(out.hdr.iter().all(|&v| (v - 0.25).abs() < 1e-6));
        assert!(out.ldr.chunks(4).all(|p| p[..3] == [77, 77, 77]));
    }
}
