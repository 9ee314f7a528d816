//! Writing frames to disk: tone-mapped PNG, linear Radiance HDR.

use std::path::Path;

use anyhow::{Context as _, Result};

use super::tone::ExposureState;

/// What a headless frame gives back.
pub struct FrameOutput {
    pub width: u32,
    pub height: u32,
    /// The final image (tone-mapped, anti-aliased unless `--aa none`): sRGB RGBA8, row-major, top row first.
    pub ldr: Vec<u8>,
    /// Linear radiance, RGBA32F.
    pub hdr: Vec<f32>,
    /// GPU milliseconds per pass.
    pub timings: Vec<(&'static str, f64)>,
    /// Rays traced by kind (camera, shadow, secondary) when `Effects::count_rays` is on, else zeros.
    pub ray_counts: [u32; 3],
    /// Pixels whose reflection/refraction tree was cut by the per-pixel ray budget or a full branch stack
    /// (`RAY_BUDGET_PER_PIXEL`, `BRANCH_STACK_SIZE`); always counted.
    pub truncated_pixels: u32,
    /// Pixels whose radiance reached tone mapping as NaN or Inf (shown magenta); always counted.
    pub bad_pixels: u32,
    /// What auto exposure measured and applied (None: fixed exposure).
    pub exposure: Option<ExposureState>,
    /// The first frame of its passes: a driver compiling shaders on first use (lavapipe) did so in `timings`.
    pub cold: bool,
}

impl FrameOutput {
    /// A frame of these pixels only: no timings, nothing counted or measured.
    pub fn from_images(width: u32, height: u32, ldr: Vec<u8>, hdr: Vec<f32>) -> FrameOutput {
        FrameOutput {
            width,
            height,
            ldr,
            hdr,
            timings: Vec::new(),
            ray_counts: [0; 3],
            truncated_pixels: 0,
            bad_pixels: 0,
            exposure: None,
            cold: false,
        }
    }

    /// GPU ms of the pass `name` (0 when the frame has none).
    pub fn pass_ms(&self, name: &str) -> f64 {
        // (+ 0.0: an empty sum is -0.0.)
        self.timings.iter().filter(|(n, _)| *n == name).map(|(_, ms)| ms).sum::<f64>() + 0.0
    }

    /// GPU ms of the frame's passes, the readback copy left out.
    pub fn frame_ms(&self) -> f64 {
        self.timings.iter().filter(|(n, _)| *n != "readback").map(|(_, ms)| ms).sum()
    }

    /// GPU ms of what effects mode's budget bounds: the ray stages (render/budget/effects.rs's STAGES)
    /// and the raster fallback's shadow maps.
    pub fn budgeted_ms(&self) -> f64 {
        use crate::render::budget::effects::{SHADOW_MAP_PASS, STAGES};
        STAGES.iter().flat_map(|s| s.iter()).chain([&SHADOW_MAP_PASS]).map(|p| self.pass_ms(p)).sum()
    }

    /// What to tell the user when reflection/refraction trees were cut.
    pub fn truncation_warning(&self) -> Option<String> {
        use crate::gpu::shared::{BRANCH_STACK_SIZE, RAY_BUDGET_PER_PIXEL};
        (self.truncated_pixels > 0).then(|| {
            format!(
                "{} pixel(s) reached the limit of {RAY_BUDGET_PER_PIXEL} secondary rays or {BRANCH_STACK_SIZE} \
                 pending branches per pixel: their reflection/refraction trees were cut (lower --max-depth or \
                 raise --min-weight)",
                self.truncated_pixels
            )
        })
    }

    /// The tone-mapped image without alpha.
    pub fn rgb8(&self) -> image::RgbImage {
        let rgb: Vec<u8> = self.ldr.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        image::RgbImage::from_raw(self.width, self.height, rgb).expect("frame size matches its pixels")
    }

    /// Linear radiance of pixel (x, y).
    pub fn radiance(&self, x: u32, y: u32) -> [f32; 3] {
        let i = ((y * self.width + x) * 4) as usize;
        [self.hdr[i], self.hdr[i + 1], self.hdr[i + 2]]
    }

    /// True when every radiance value is finite (no NaN/Inf reached the frame).
    pub fn all_finite(&self) -> bool {
        self.hdr.iter().all(|v| v.is_finite())
    }

    pub fn save_png(&self, path: &Path) -> Result<()> {
        create_parent(path)?;
        self.rgb8().save(path).with_context(|| format!("writing {}", path.display()))
    }

    /// Linear HDR output (Radiance RGBE .hdr).
    pub fn save_hdr(&self, path: &Path) -> Result<()> {
        create_parent(path)?;
        let file = std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
        let pixels: Vec<image::Rgb<f32>> = self
            .hdr
            .chunks_exact(4)
            .map(|p| image::Rgb([p[0].max(0.0), p[1].max(0.0), p[2].max(0.0)]))
            .collect();
        image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(file))
            .encode(&pixels, self.width as usize, self.height as usize)
            .with_context(|| format!("writing {}", path.display()))
    }
}

fn create_parent(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating directory {}", dir.display()))?;
    }
    Ok(())
}
