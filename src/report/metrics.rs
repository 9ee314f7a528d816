//! Image error: ꟻLIP (NVIDIA's reference implementation through `nv-flip`)
//! on LDR images, PSNR and relative MSE on linear HDR images.
//!
//! As the ꟻLIP authors recommend for a renderer with its own tone mapper, HDR frames both go through
//! glsl/tonemap.comp at the *reference's* frozen exposure and LDR-ꟻLIP compares the results; the
//! linear radiance is compared directly by PSNR and relMSE.

use anyhow::{ensure, Result};

use crate::render::srgb::linear_to_srgb;

/// A linear RGB image (radiance), row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<f32>,
}

/// An 8-bit sRGB image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct LdrImage {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

impl HdrImage {
    /// From RGBA32F (a frame's readback); non-finite values become 0 and
    /// are counted (second value).
    pub fn from_rgba(width: u32, height: u32, rgba: &[f32]) -> (HdrImage, usize) {
        let mut non_finite = 0;
        let mut rgb = Vec::with_capacity(width as usize * height as usize * 3);
        for p in rgba.chunks_exact(4) {
            if !p[..3].iter().all(|v| v.is_finite()) {
                non_finite += 1;
                rgb.extend_from_slice(&[0.0; 3]);
            } else {
                rgb.extend_from_slice(&p[..3]);
            }
        }
        (HdrImage { width, height, rgb }, non_finite)
    }

    fn at(&self, x: u32, y: u32) -> [f32; 3] {
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Bilinear resampling of the linear radiance to `width` x `height`
    /// (pixel centres aligned, edges clamped): how a lower-resolution frame
    /// is brought to the reference's size before it is compared.
    pub fn resized(&self, width: u32, height: u32) -> HdrImage {
        if (width, height) == (self.width, self.height) {
            return self.clone();
        }
        let (sx, sy) = (self.width as f32 / width as f32, self.height as f32 / height as f32);
        let mut rgb = Vec::with_capacity(width as usize * height as usize * 3);
        for y in 0..height {
            let fy = ((y as f32 + 0.5) * sy - 0.5).clamp(0.0, (self.height - 1) as f32);
            let (y0, ty) = (fy.floor() as u32, fy.fract());
            let y1 = (y0 + 1).min(self.height - 1);
            for x in 0..width {
                let fx = ((x as f32 + 0.5) * sx - 0.5).clamp(0.0, (self.width - 1) as f32);
                let (x0, tx) = (fx.floor() as u32, fx.fract());
                let x1 = (x0 + 1).min(self.width - 1);
                let (a, b, c, d) = (self.at(x0, y0), self.at(x1, y0), self.at(x0, y1), self.at(x1, y1));
                for k in 0..3 {
                    let top = a[k] + (b[k] - a[k]) * tx;
                    let bottom = c[k] + (d[k] - c[k]) * tx;
                    rgb.push(top + (bottom - top) * ty);
                }
            }
        }
        HdrImage { width, height, rgb }
    }

    /// The renderer's tone mapper on the CPU (glsl/tonemap.comp): exposure,
    /// Reinhard on luminance, clamp, sRGB encoding, rounded to 8 bits.
    pub fn tone_mapped(&self, exposure: f32) -> LdrImage {
        let rgb = self
            .rgb
            .chunks_exact(3)
            .flat_map(|p| {
                let c = [p[0] * exposure, p[1] * exposure, p[2] * exposure];
                let l = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
                let s = if l > 0.0 { 1.0 / (1.0 + l) } else { 1.0 };
                c.map(|v| (linear_to_srgb(v * s) * 255.0 + 0.5) as u8)
            })
            .collect();
        LdrImage { width: self.width, height: self.height, rgb }
    }
}

/// A per-pixel ꟻLIP error map (values in [0, 1]).
pub struct FlipMap {
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
    /// The error map through ꟻLIP's magma colour map, RGB8.
    pub magma: Vec<u8>,
}

impl FlipMap {
    /// The mean error, as ꟻLIP's own tool reports it.
    pub fn mean(&self) -> f64 {
        self.values.iter().map(|&v| v as f64).sum::<f64>() / self.values.len().max(1) as f64
    }

    /// Share of pixels whose error exceeds `threshold`.
    pub fn share_over(&self, threshold: f32) -> f64 {
        self.values.iter().filter(|&&v| v > threshold).count() as f64 / self.values.len().max(1) as f64
    }

    pub fn save_png(&self, path: &std::path::Path) -> Result<()> {
        use anyhow::Context as _;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating directory {}", dir.display()))?;
        }
        image::RgbImage::from_raw(self.width, self.height, self.magma.clone())
            .context("error map size")?
            .save(path)
            .with_context(|| format!("writing {}", path.display()))
    }
}

/// LDR-ꟻLIP of `test` against `reference` (sRGB images of one size), at
/// ꟻLIP's default 67 pixels per degree (a 0.7 m view of a 24" 4K screen).
pub fn flip(reference: &LdrImage, test: &LdrImage) -> Result<FlipMap> {
    ensure!(
        (reference.width, reference.height) == (test.width, test.height),
        "ꟻLIP needs images of one size: reference {}x{}, test {}x{}",
        reference.width,
        reference.height,
        test.width,
        test.height
    );
    ensure!(reference.width > 0 && reference.height > 0, "ꟻLIP of an empty image");
    let r = nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &reference.rgb);
    let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &test.rgb);
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let magma = map.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    Ok(FlipMap { width: map.width(), height: map.height(), values: map.to_vec(), magma })
}

/// PSNR in dB of linear radiance, with the reference's largest channel
/// value as the peak: 10 log10(peak^2 / MSE) over all RGB values.
/// Infinite for identical images.
pub fn psnr_hdr(reference: &HdrImage, test: &HdrImage) -> f64 {
    let peak = reference.rgb.iter().fold(0.0f32, |m, &v| m.max(v)).max(1e-6) as f64;
    let mse = mse(reference, test);
    if mse == 0.0 {
        return f64::INFINITY;
    }
    10.0 * (peak * peak / mse).log10()
}

fn mse(reference: &HdrImage, test: &HdrImage) -> f64 {
    let sum: f64 = reference.rgb.iter().zip(&test.rgb).map(|(&a, &b)| ((a - b) as f64).powi(2)).sum();
    sum / reference.rgb.len().max(1) as f64
}

/// Relative MSE of linear radiance: the mean over RGB values of
/// (test - ref)^2 / (ref^2 + 0.01), the denoising literature's relMSE.
pub fn rel_mse(reference: &HdrImage, test: &HdrImage) -> f64 {
    let sum: f64 = reference
        .rgb
        .iter()
        .zip(&test.rgb)
        .map(|(&r, &t)| {
            let (r, t) = (r as f64, t as f64);
            (t - r).powi(2) / (r * r + 0.01)
        })
        .sum();
    sum / reference.rgb.len().max(1) as f64
}

/// Every error number of `test` against `reference`.
pub struct Errors {
    pub flip_mean: f64,
    pub psnr: f64,
    pub rel_mse: f64,
    pub map: FlipMap,
    /// The tone-mapped 8-bit images' largest channel difference and the
    /// share of pixels that differ at all (what a small ꟻLIP is made of).
    pub ldr: LdrDiff,
}

/// How two 8-bit images differ, channel values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdrDiff {
    pub max: u8,
    pub share_differing: f64,
}

impl LdrDiff {
    pub fn of(a: &LdrImage, b: &LdrImage) -> LdrDiff {
        let (max, share_differing) = crate::image_diff::diff_stats(&a.rgb, &b.rgb, 3, 0);
        LdrDiff { max, share_differing }
    }

    pub fn describe(&self) -> String {
        format!(
            "largest 8-bit channel difference {}, {:.1}% of pixels differ",
            self.max,
            self.share_differing * 100.0
        )
    }
}

/// `test` (any size: resampled to the reference's) against `reference`,
/// both tone-mapped with `exposure` (the reference's) for ꟻLIP.
pub fn compare_hdr(reference: &HdrImage, test: &HdrImage, exposure: f32) -> Result<Errors> {
    let test = test.resized(reference.width, reference.height);
    let (r, t) = (reference.tone_mapped(exposure), test.tone_mapped(exposure));
    let map = flip(&r, &t)?;
    Ok(Errors {
        flip_mean: map.mean(),
        psnr: psnr_hdr(reference, &test),
        rel_mse: rel_mse(reference, &test),
        map,
        ldr: LdrDiff::of(&r, &t),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient(w: u32, h: u32, shift: u32) -> HdrImage {
        let mut rgb = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = (((x + shift) % w) as f32 / w as f32) * 2.0 + (y % 3) as f32 * 0.3;
                rgb.extend_from_slice(&[v, v * 0.5, 1.0 - v * 0.2]);
            }
        }
        HdrImage { width: w, height: h, rgb }
    }

    #[test]
    fn identical_images_have_no_error_and_shifted_ones_do() {
        let a = gradient(32, 18, 0);
        let same = compare_hdr(&a, &a, 1.0).unwrap();
        assert_eq!(same.flip_mean, 0.0);
        assert!(same.psnr.is_infinite() && same.rel_mse == 0.0);
        let shifted = compare_hdr(&a, &gradient(32, 18, 3), 1.0).unwrap();
        assert!(shifted.flip_mean > 0.0 && shifted.psnr.is_finite() && shifted.rel_mse > 0.0);
        assert!(shifted.map.share_over(0.0) > 0.0);
    }

    #[test]
    fn tone_mapper_matches_the_shader() {
        // Luminance 1 at exposure 1: Reinhard halves it; 0.5 -> sRGB 188.
        let img = HdrImage { width: 1, height: 1, rgb: vec![1.0, 1.0, 1.0] };
        assert_eq!(img.tone_mapped(1.0).rgb, vec![188, 188, 188]);
        let black = HdrImage { width: 1, height: 1, rgb: vec![0.0; 3] };
        assert_eq!(black.tone_mapped(4.0).rgb, vec![0, 0, 0]);
    }

    #[test]
    fn psnr_uses_the_reference_peak() {
        let a = HdrImage { width: 1, height: 1, rgb: vec![10.0, 0.0, 0.0] };
        let b = HdrImage { width: 1, height: 1, rgb: vec![10.0, 0.0, 3.0_f32.sqrt()] };
        // MSE 1, peak 10 -> 20 dB.
        assert!((psnr_hdr(&a, &b) - 20.0).abs() < 1e-4, "{}", psnr_hdr(&a, &b));
    }

    #[test]
    fn resampling_keeps_constant_images_and_sizes() {
        let c = HdrImage { width: 4, height: 2, rgb: vec![0.25; 24] };
        let r = c.resized(8, 4);
        assert_eq!((r.width, r.height, r.rgb.len()), (8, 4, 96));
        assert!(r.rgb.iter().all(|&v| (v - 0.25).abs() < 1e-6));
        assert!(flip(&c.tone_mapped(1.0), &r.tone_mapped(1.0)).is_err());
    }
}
