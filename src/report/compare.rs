//! `compare A B`: the report's metric on two image files. PNG against PNG
//! is LDR-ꟻLIP and 8-bit PSNR; Radiance .hdr against .hdr tone-maps both
//! with one exposure (A is the reference) for ꟻLIP and compares the linear
//! radiance for PSNR and relMSE.

use std::path::Path;

use anyhow::{bail, Context as _, Result};

use super::metrics::{self, HdrImage, LdrImage};

enum Loaded {
    Ldr(LdrImage),
    Hdr(HdrImage),
}

impl Loaded {
    fn size(&self) -> (u32, u32) {
        match self {
            Loaded::Ldr(i) => (i.width, i.height),
            Loaded::Hdr(i) => (i.width, i.height),
        }
    }
}

fn is_hdr(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("hdr"))
}

fn load(path: &Path) -> Result<Loaded> {
    let img = image::ImageReader::open(path)
        .with_context(|| format!("cannot open {}", path.display()))?
        .with_guessed_format()
        .with_context(|| format!("cannot read {}", path.display()))?
        .decode()
        .with_context(|| format!("cannot decode {}", path.display()))?;
    let (width, height) = (img.width(), img.height());
    if width == 0 || height == 0 {
        bail!("{} is empty ({width}x{height})", path.display());
    }
    Ok(
        if is_hdr(path)
            || matches!(img, image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_))
        {
            Loaded::Hdr(HdrImage { width, height, rgb: img.into_rgb32f().into_raw() })
        } else {
            Loaded::Ldr(LdrImage { width, height, rgb: img.into_rgb8().into_raw() })
        },
    )
}

/// What `compare` prints.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub width: u32,
    pub height: u32,
    pub hdr: bool,
    pub flip_mean: f64,
    /// dB: 8-bit for PNG, linear radiance (peak = A's largest value) for HDR.
    pub psnr: f64,
    /// Linear radiance only.
    pub rel_mse: Option<f64>,
    pub threshold: f32,
    /// Share of pixels whose ꟻLIP error exceeds `threshold`.
    pub share_over: f64,
    /// The 8-bit images (tone-mapped for HDR) compared value by value.
    pub ldr: metrics::LdrDiff,
}

impl Comparison {
    pub fn summary(&self) -> String {
        let kind = if self.hdr { "HDR (tone-mapped for ꟻLIP, linear PSNR)" } else { "LDR" };
        let mut s = format!(
            "{}x{} {kind}\nꟻLIP mean {:.6}\nPSNR {} dB\npixels with ꟻLIP > {}: {:.3}%\n",
            self.width,
            self.height,
            self.flip_mean,
            if self.psnr.is_infinite() { "inf".to_string() } else { format!("{:.3}", self.psnr) },
            self.threshold,
            self.share_over * 100.0
        );
        if let Some(r) = self.rel_mse {
            s.push_str(&format!("relMSE {r:.6}\n"));
        }
        s.push_str(&format!("{}\n", self.ldr.describe()));
        s
    }
}

/// Compares `b` against the reference `a`; writes the ꟻLIP error map
/// (magma) to `map` when given.
pub fn compare(a: &Path, b: &Path, map: Option<&Path>, threshold: f32, exposure: f32) -> Result<Comparison> {
    let (ia, ib) = (load(a)?, load(b)?);
    if ia.size() != ib.size() {
        let ((wa, ha), (wb, hb)) = (ia.size(), ib.size());
        bail!("the images differ in size: {} is {wa}x{ha}, {} is {wb}x{hb}", a.display(), b.display());
    }
    let (width, height) = ia.size();
    let (flip, psnr, rel_mse, hdr, ldr) = match (&ia, &ib) {
        (Loaded::Ldr(x), Loaded::Ldr(y)) => {
            let psnr = crate::image_diff::psnr_rgb8(&x.rgb, &y.rgb, 3, None);
            (metrics::flip(x, y)?, psnr, None, false, metrics::LdrDiff::of(x, y))
        }
        (Loaded::Hdr(x), Loaded::Hdr(y)) => {
            let e = metrics::compare_hdr(x, y, exposure)?;
            (e.map, e.psnr, Some(e.rel_mse), true, e.ldr)
        }
        (Loaded::Hdr(_), Loaded::Ldr(_)) | (Loaded::Ldr(_), Loaded::Hdr(_)) => {
            let (h, l) = if matches!(ia, Loaded::Hdr(_)) { (a, b) } else { (b, a) };
            bail!(
                "{} is HDR and {} is LDR: compare two .hdr files or two PNGs (render --hdr-out writes both kinds)",
                h.display(),
                l.display()
            );
        }
    };
    if let Some(path) = map {
        flip.save_png(path)?;
    }
    Ok(Comparison {
        width,
        height,
        hdr,
        flip_mean: flip.mean(),
        psnr,
        rel_mse,
        threshold,
        share_over: flip.share_over(threshold),
        ldr,
    })
}
