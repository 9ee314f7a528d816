//! Environment-map layouts read on import. The renderer samples
//! equirectangular maps only (glsl/common/env.glsl); other layouts are
//! converted to it on load.
//!
//! Angular map (Debevec's light-probe layout): a square image whose centre
//! looks forward, whose circumference is straight back, and whose distance
//! from the centre is linear in the angle from forward. "Forward" is -Z, the
//! direction the equirect map's centre column (u = 0.5) shows, so a probe
//! converted here shows the same view in the middle of the background. With
//! image coordinates (a, b) in [-1, 1]^2 (a right, b up), a direction d reads
//!
//! ```text
//! r = acos(-d.z) / (pi * sqrt(d.x^2 + d.y^2)),   (a, b) = (d.x r, d.y r)
//! ```
//!
//! (Debevec, "Light Probe Image Gallery", with his forward axis -Z).

use std::f64::consts::PI;
use std::path::Path;

use anyhow::{ensure, Result};
use glam::DVec3;

use super::hdr_image::HdrImage;
use super::sh::texel_dir;

/// How an environment image maps directions to texels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum EnvLayout {
    /// Latitude-longitude, 2:1 (the renderer's own layout).
    #[default]
    Equirect,
    /// Debevec's angular light probe (square), converted to equirect.
    Angular,
}

/// The angular-map coordinates (a, b) in [-1, 1]^2, b up, that `dir` reads.
pub fn angular_coords(dir: DVec3) -> (f64, f64) {
    let d = dir.normalize();
    let s = (d.x * d.x + d.y * d.y).sqrt();
    if s < 1e-12 {
        // Straight forward is the centre; straight back is the rim (any
        // point of it: take the right edge).
        return if d.z < 0.0 { (0.0, 0.0) } else { (1.0, 0.0) };
    }
    let r = (-d.z).clamp(-1.0, 1.0).acos() / (PI * s);
    (d.x * r, d.y * r)
}

/// Converts a square angular map to an equirect map of 2N x N texels
/// (N = the probe's side), bilinear reads clamped to the probe's disc
/// square. `path` names the file in errors.
pub fn angular_to_equirect(probe: &HdrImage, path: &Path) -> Result<HdrImage> {
    let n = probe.width;
    ensure!(
        n == probe.height && n > 0,
        "{}: an angular light probe must be square (got {}x{})",
        path.display(),
        probe.width,
        probe.height
    );
    let (w, h) = (2 * n, n);
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h {
        for x in 0..w {
            let (a, b) = angular_coords(texel_dir(x, y, w, h, 0.0));
            // Texel centres at (i + 0.5) / n; b = +1 is the top row.
            let px = (a + 1.0) * 0.5 * n as f64 - 0.5;
            let py = (1.0 - b) * 0.5 * n as f64 - 0.5;
            rgb.extend_from_slice(&bilinear(probe, px, py));
        }
    }
    Ok(HdrImage { width: w, height: h, rgb })
}

fn bilinear(img: &HdrImage, px: f64, py: f64) -> [f32; 3] {
    let max = (img.width - 1) as f64;
    let (px, py) = (px.clamp(0.0, max), py.clamp(0.0, (img.height - 1) as f64));
    let (x0, y0) = (px.floor() as u32, py.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(img.width - 1), (y0 + 1).min(img.height - 1));
    let (fx, fy) = ((px - x0 as f64) as f32, (py - y0 as f64) as f32);
    let at = |x: u32, y: u32, k: usize| img.rgb[((y * img.width + x) * 3) as usize + k];
    [0, 1, 2].map(|k| {
        let top = at(x0, y0, k) * (1.0 - fx) + at(x1, y0, k) * fx;
        let bottom = at(x0, y1, k) * (1.0 - fx) + at(x1, y1, k) * fx;
        top * (1.0 - fy) + bottom * fy
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::sh::env_uv;

    #[test]
    fn angular_axes() {
        let close = |(a, b): (f64, f64), (x, y): (f64, f64)| (a - x).abs() < 1e-12 && (b - y).abs() < 1e-12;
        assert!(close(angular_coords(DVec3::NEG_Z), (0.0, 0.0)));
        // 90 degrees off forward: half way to the rim.
        assert!(close(angular_coords(DVec3::X), (0.5, 0.0)));
        assert!(close(angular_coords(DVec3::NEG_X), (-0.5, 0.0)));
        assert!(close(angular_coords(DVec3::Y), (0.0, 0.5)));
        let back = angular_coords(DVec3::new(1e-6, 0.0, 1.0));
        assert!((back.0 - 1.0).abs() < 1e-6, "{back:?}");
    }

    /// A probe lit only in one small spot around a known direction: after
    /// conversion the equirect texels that light up read that direction.
    #[test]
    fn converted_probe_keeps_directions() {
        let n = 64u32;
        for target in
            [DVec3::X, DVec3::new(0.3, 0.8, -0.5).normalize(), DVec3::new(-0.6, -0.2, 0.7).normalize()]
        {
            let mut probe = HdrImage { width: n, height: n, rgb: vec![0.0; (n * n * 3) as usize] };
            let (a, b) = angular_coords(target);
            let (cx, cy) = ((a + 1.0) * 0.5 * n as f64, (1.0 - b) * 0.5 * n as f64);
            for y in 0..n {
                for x in 0..n {
                    if (x as f64 + 0.5 - cx).hypot(y as f64 + 0.5 - cy) < 2.0 {
                        probe.rgb[((y * n + x) * 3) as usize] = 1.0;
                    }
                }
            }
            let eq = angular_to_equirect(&probe, Path::new("probe.hdr")).unwrap();
            assert_eq!((eq.width, eq.height), (2 * n, n));
            // Radiance-weighted mean direction of the lit texels.
            let mut sum = DVec3::ZERO;
            for y in 0..eq.height {
                for x in 0..eq.width {
                    let v = eq.rgb[((y * eq.width + x) * 3) as usize] as f64;
                    sum += texel_dir(x, y, eq.width, eq.height, 0.0) * v;
                }
            }
            assert!(sum.length() > 0.0, "nothing lit for {target}");
            let got = sum.normalize();
            assert!(got.dot(target) > 0.99, "{target}: lit around {got}");
            // And the equirect lookup of the target lands on a lit texel.
            let (u, v) = env_uv(target, 0.0);
            let (x, y) = ((u.rem_euclid(1.0) * eq.width as f64) as u32, (v * eq.height as f64) as u32);
            assert!(eq.rgb[((y * eq.width + x) * 3) as usize] > 0.0, "{target}: texel ({x}, {y}) dark");
        }
    }

    #[test]
    fn non_square_probe_is_an_error() {
        let probe = HdrImage { width: 4, height: 2, rgb: vec![0.0; 24] };
        let e = angular_to_equirect(&probe, Path::new("dir/probe.hdr")).unwrap_err().to_string();
        assert!(e.contains("dir/probe.hdr") && e.contains("square") && e.contains("4x2"), "{e}");
    }
}
