//! The report's default reference: the path-traced truth of the view (render/path.rs), so each knob's
//! error is its distance from the true image, not from the renderer's deepest setting. Its own noise
//! (two halves compared with ꟻLIP) is reported; `run` doubles samples until it is under half the
//! smallest error (up to a cap). Converged images are cached by content (scene, view, size, path
//! settings, path shaders' SPIR-V); a short, corrupt or foreign file is re-rendered with a warning.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context as _, Result};

use super::knobs::Variant;
use super::measure::{median_p95, Measured, Timing};
use super::metrics::{self, HdrImage};
use crate::gpu::shared::PATH_SAMPLES_PER_FRAME;
use crate::render::Renderer;
use crate::scene::{Camera, Scene};
use crate::vk::Context;

/// Overrides the cache directory.
pub const CACHE_DIR_ENV: &str = "HYBRID_RT_TRUTH_CACHE";
const MAGIC: &[u8; 8] = b"HRTTRUT\x01";

/// `$HYBRID_RT_TRUTH_CACHE`, else `$XDG_CACHE_HOME/hybrid-rt/truth`, else
/// `~/.cache/hybrid-rt/truth`; `None` without any of them.
pub fn default_cache_dir() -> Option<PathBuf> {
    crate::prt::user_cache_dir(CACHE_DIR_ENV, "truth")
}

/// The path-traced reference of one view: how it was made (its image is
/// the report's `measured[0]`).
#[derive(Clone, Debug)]
pub struct Truth {
    /// Paths per pixel.
    pub samples: u32,
    /// The images of the first and the second half of the samples (two
    /// independent estimates at half the count) against each other.
    pub halves_flip: f64,
    pub halves_psnr: f64,
    pub halves_ldr: metrics::LdrDiff,
    /// Wall time of its frames when it was rendered.
    pub seconds: f64,
    /// Read from the cache file.
    pub cached: bool,
}

impl Truth {
    /// The reference's own distance to its limit, estimated: two halves
    /// differ by about twice what the whole differs from the limit (noise
    /// falls as 1/sqrt(N); ꟻLIP of small differences is close to linear).
    pub fn noise(&self) -> f64 {
        self.halves_flip / 2.0
    }
}

struct Fnv(u64);
impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, b: &[u8]) {
        self.u64(b.len() as u64);
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
    fn u64(&mut self, v: u64) {
        for x in v.to_le_bytes() {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
    fn text(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
}

/// Everything the path-traced image depends on: the posed scene's
/// instances, geometry, materials, textures, lights and environment, the
/// camera, the size, the path settings and the path shaders themselves.
pub fn key(scene: &Scene, camera: &Camera, w: u32, h: u32, variant: &Variant) -> u64 {
    let mut f = Fnv::new();
    f.text(&format!("{:?} {:?} {w}x{h}", variant.settings.path, variant.settings.backend));
    f.text(&format!("{:?}", camera));
    for inst in &scene.instances {
        f.text(&format!("{inst:?}"));
        let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
        f.bytes(bytemuck::cast_slice(&prim.vertices));
        f.bytes(bytemuck::cast_slice(&prim.indices));
    }
    for m in &scene.materials {
        f.text(&format!("{m:?}"));
    }
    for t in &scene.textures {
        f.text(&format!("{} {}x{} {} {:?}", t.name, t.width, t.height, t.srgb, t.sampler));
        f.bytes(&t.rgba8);
    }
    for l in &scene.lights {
        f.text(&format!("{l:?}"));
    }
    for o in &scene.objects {
        f.text(&format!("{:?}", o.props));
    }
    let e = &scene.environment;
    f.text(&format!("{:?} {} {}", e.color, e.intensity, e.rotation));
    if let Some(map) = &e.map {
        f.text(&format!("{}x{}", map.width, map.height));
        f.bytes(bytemuck::cast_slice(&map.rgb));
    }
    for shader in ["path_query", "path_compute", "path.rgen"] {
        if let Ok(words) = crate::vk::pipeline::spirv(shader) {
            f.bytes(bytemuck::cast_slice(&words));
        }
    }
    f.0
}

/// The truth of `variant` (a `--mode path` setting) with at least `samples`
/// paths per pixel: read from `cache` when a file there holds as many, else
/// rendered (and written there).
#[allow(clippy::too_many_arguments)]
pub fn truth(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    variant: &Variant,
    samples: u32,
    exposure: f32,
    cache: Option<&Path>,
) -> Result<(Measured, Truth)> {
    let (w, h) = (renderer.extent().width, renderer.extent().height);
    let k = key(scene, camera, w, h, variant);
    let file = cache.map(|d| d.join(format!("{k:016x}.truth")));
    if let Some(path) = file.as_ref().filter(|p| p.exists()) {
        match read(path, k, w, h) {
            Ok(c) if c.truth.samples >= samples => {
                let n = c.truth.samples;
                log::info!("report: the path-traced reference ({n} samples) read from {}", path.display());
                let t = Truth { cached: true, ..c.truth.clone() };
                let image = HdrImage { width: w, height: h, rgb: c.rgb };
                return Ok((measured(variant, image, c.timing, exposure), t));
            }
            Ok(c) => log::info!(
                "report: {} holds {} samples, {samples} wanted: rendering",
                path.display(),
                c.truth.samples
            ),
            Err(e) => {
                log::warn!("report: ignoring cache file {}: {e:#}; rendering the reference", path.display())
            }
        }
    }
    let (m, t) = render(ctx, renderer, scene, camera, variant, samples, exposure)?;
    if let Some(path) = &file {
        let c = Cached { truth: t.clone(), timing: m.timing.clone(), rgb: m.image.rgb.clone() };
        match write(path, k, w, h, &c) {
            Ok(()) => log::info!("report: cached the path-traced reference in {}", path.display()),
            Err(e) => log::warn!("report: could not cache the reference in {}: {e:#}", path.display()),
        }
    }
    Ok((m, t))
}

/// Renders the truth from scratch: half the samples, then the other half
/// on top, so the two halves can be told apart.
fn render(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    variant: &Variant,
    samples: u32,
    exposure: f32,
) -> Result<(Measured, Truth)> {
    let half_frames = samples.div_ceil(2 * PATH_SAMPLES_PER_FRAME).max(1);
    let total = 2 * half_frames * PATH_SAMPLES_PER_FRAME;
    let settings = variant.settings;
    renderer.reset_reference();
    let start = Instant::now();
    let mut last_log = Instant::now();
    let (mut totals, mut path_ms) = (Vec::new(), Vec::new());
    let mut first_half = None;
    let mut out = None;
    for i in 0..2 * half_frames {
        let o = renderer.render(ctx, scene, camera, &settings)?;
        totals.push(o.timings.iter().filter(|(n, _)| *n != "readback").map(|(_, ms)| ms).sum::<f64>());
        path_ms.push(o.pass_ms(crate::render::passes::path::PASS.name));
        if i + 1 == half_frames {
            first_half = Some(o.hdr.clone());
        }
        if last_log.elapsed().as_secs_f64() >= 5.0 {
            last_log = Instant::now();
            eprintln!(
                "report: path-traced reference {}% ({} of {total} samples per pixel, {:.0} s)",
                100 * (i + 1) / (2 * half_frames),
                (i + 1) * PATH_SAMPLES_PER_FRAME,
                start.elapsed().as_secs_f64()
            );
        }
        out = Some(o);
    }
    let out = out.context("no frame rendered")?;
    if renderer.reference_frames() != 2 * half_frames {
        bail!(
            "the path-traced reference restarted part-way ({} frames accumulated)",
            renderer.reference_frames()
        );
    }
    let first = first_half.context("no half-way frame")?;
    let Halves { full, non_finite, first: a, second: b } =
        Halves::of(out.width, out.height, &out.hdr, &first);
    let halves = metrics::compare_hdr(&a, &b, exposure)?;
    let (median, p95) = median_p95(&totals);
    let timing = Timing {
        median,
        p95,
        passes: vec![(crate::render::passes::path::PASS.name, median_p95(&path_ms).0)],
        frames: totals.len(),
    };
    let seconds = start.elapsed().as_secs_f64();
    eprintln!(
        "report: path-traced reference: {total} samples per pixel in {seconds:.1} s; its halves differ by ꟻLIP \
         {:.5}",
        halves.flip_mean
    );
    let config = renderer.shading_config();
    let mut measured = measured(variant, full, timing, exposure);
    measured.non_finite = non_finite;
    measured.config = config.map(|c| c.describe()).unwrap_or_default();
    measured.backend = config.and_then(|c| c.backend).map_or("none".into(), |b| b.name().into());
    let truth = Truth {
        samples: total,
        halves_flip: halves.flip_mean,
        halves_psnr: halves.psnr,
        halves_ldr: halves.ldr,
        seconds,
        cached: false,
    };
    Ok((measured, truth))
}

/// An accumulation read back whole and half-way: the whole image, its
/// non-finite pixels, and its two halves as independent images.
pub(super) struct Halves {
    pub full: HdrImage,
    pub non_finite: usize,
    pub first: HdrImage,
    pub second: HdrImage,
}

impl Halves {
    /// From the RGBA mean of all frames and the mean of the first half.
    pub fn of(width: u32, height: u32, full: &[f32], first: &[f32]) -> Halves {
        // The second half alone: twice the whole's mean minus the first half's.
        let second: Vec<f32> = full.iter().zip(first).map(|(f, a)| 2.0 * f - a).collect();
        let (full, non_finite) = HdrImage::from_rgba(width, height, full);
        let image = |v: &[f32]| HdrImage::from_rgba(width, height, v).0;
        Halves { full, non_finite, first: image(first), second: image(&second) }
    }
}

fn measured(variant: &Variant, image: HdrImage, timing: Timing, exposure: f32) -> Measured {
    let ldr = image.tone_mapped(exposure);
    Measured {
        variant: *variant,
        config: "mode Path: the path-traced ground truth".into(),
        backend: variant.settings.backend.name().into(),
        width: image.width,
        height: image.height,
        timing,
        rays: None,
        image,
        ldr,
        non_finite: 0,
        exposure: None,
    }
}

/// A cache file's content.
#[derive(Debug)]
struct Cached {
    truth: Truth,
    timing: Timing,
    rgb: Vec<f32>,
}

const HEAD: usize = 8 + 8 + 6 * 4 + 7 * 8;

fn write(path: &Path, key: u64, w: u32, h: u32, c: &Cached) -> Result<()> {
    let dir = path.parent().context("no directory")?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let t = &c.truth;
    let mut b = Vec::with_capacity(HEAD + c.rgb.len() * 4);
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&key.to_le_bytes());
    for v in [w, h, t.samples, c.timing.frames as u32, t.halves_ldr.max as u32, 0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    let path_ms = c.timing.pass("path").unwrap_or(f64::NAN);
    for v in [
        t.halves_flip,
        t.halves_psnr,
        t.halves_ldr.share_differing,
        t.seconds,
        c.timing.median,
        c.timing.p95,
        path_ms,
    ] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(bytemuck::cast_slice(&c.rgb));
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, &b).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
}

fn read(path: &Path, key: u64, w: u32, h: u32) -> Result<Cached> {
    let b = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    if b.len() < HEAD || &b[..8] != MAGIC {
        bail!("not a reference cache file (or an older format)");
    }
    let u32_at = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().expect("4 bytes"));
    let f64_at = |i: usize| f64::from_le_bytes(b[i..i + 8].try_into().expect("8 bytes"));
    if u64::from_le_bytes(b[8..16].try_into().expect("8 bytes")) != key {
        bail!("written for another scene, view or renderer (key mismatch)");
    }
    let (width, height, samples, frames, ldr_max) =
        (u32_at(16), u32_at(20), u32_at(24), u32_at(28), u32_at(32));
    if (width, height) != (w, h) {
        bail!("{width}x{height}, not {w}x{h}");
    }
    let floats = (w * h * 3) as usize;
    if b.len() != HEAD + floats * 4 {
        bail!("{} bytes, {} expected (truncated?)", b.len(), HEAD + floats * 4);
    }
    let rgb: Vec<f32> = bytemuck::pod_collect_to_vec(&b[HEAD..]);
    let f = 40;
    let (halves_flip, halves_psnr, share) = (f64_at(f), f64_at(f + 8), f64_at(f + 16));
    if !rgb.iter().all(|v| v.is_finite() && *v >= 0.0)
        || !halves_flip.is_finite()
        || samples == 0
        || ldr_max > 255
    {
        bail!("corrupt: non-finite or out-of-range values");
    }
    let truth = Truth {
        samples,
        halves_flip,
        halves_psnr,
        halves_ldr: metrics::LdrDiff { max: ldr_max as u8, share_differing: share },
        seconds: f64_at(f + 24),
        cached: true,
    };
    let timing = Timing {
        median: f64_at(f + 32),
        p95: f64_at(f + 40),
        passes: vec![(crate::render::passes::path::PASS.name, f64_at(f + 48))],
        frames: frames as usize,
    };
    Ok(Cached { truth, timing, rgb })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cached() -> Cached {
        let timing = Timing { median: 2.0, p95: 3.0, passes: vec![("path", 1.5)], frames: 8 };
        let truth = Truth {
            samples: 32,
            halves_flip: 0.01,
            halves_psnr: 40.0,
            halves_ldr: metrics::LdrDiff { max: 9, share_differing: 0.5 },
            seconds: 1.0,
            cached: false,
        };
        Cached { truth, timing, rgb: vec![0.5; 18] }
    }

    #[test]
    fn cache_files_round_trip_and_bad_ones_are_refused() {
        let dir = std::env::temp_dir().join(format!("hybrid-rt-truth-test-{}", std::process::id()));
        let path = dir.join("a.truth");
        write(&path, 7, 3, 2, &cached()).unwrap();
        let c = read(&path, 7, 3, 2).unwrap();
        assert_eq!(
            (c.truth.samples, c.truth.halves_flip, c.truth.halves_psnr, c.rgb.len()),
            (32, 0.01, 40.0, 18)
        );
        assert_eq!(
            (c.truth.halves_ldr.max, c.truth.halves_ldr.share_differing, c.truth.seconds),
            (9, 0.5, 1.0)
        );
        assert_eq!(c.timing, cached().timing);
        // Another key, another size, a truncated file, a foreign file, NaN.
        assert!(read(&path, 8, 3, 2).unwrap_err().to_string().contains("key"));
        assert!(read(&path, 7, 2, 3).is_err());
        let full = std::fs::read(&path).unwrap();
        std::fs::write(&path, &full[..full.len() - 4]).unwrap();
        assert!(read(&path, 7, 3, 2).unwrap_err().to_string().contains("truncated"));
        std::fs::write(&path, [7u8; 200]).unwrap();
        assert!(read(&path, 7, 3, 2).unwrap_err().to_string().contains("not a reference cache"));
        let mut bad = cached();
        bad.rgb[4] = f32::NAN;
        write(&path, 7, 3, 2, &bad).unwrap();
        assert!(read(&path, 7, 3, 2).unwrap_err().to_string().contains("corrupt"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
