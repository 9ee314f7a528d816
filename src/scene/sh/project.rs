//! Projection of an equirectangular [`HdrImage`] onto the SH basis, on the CPU.
//!
//! The map is read as env.glsl reads it: u = (atan2(d.x, -d.z) + rotation) / 2pi + 0.5,
//! v = acos(d.y) / pi (v = 0 is +Y), texel (x, y) covering [x/w, (x+1)/w] x [y/h, (y+1)/h], radiance
//! times `intensity`. Two integrators of L_lm = ∫ L(w) y_lm(w) dw:
//!
//! - [`project_quadrature`]: midpoint rule per texel with its exact solid angle
//!   (2pi / w)(cos theta_top - cos theta_bottom) (weights sum to 4pi exactly); the basis is still
//!   sampled once per texel, an O(texel^2) error for smooth y_lm.
//! - [`project_monte_carlo`]: Green's stratified jittered N x N grid mapped uniformly to the sphere,
//!   weight 4pi / N^2, nearest-texel lookups so both integrate the same piecewise-constant map
//!   (bilinear would converge to a smoothed one). Seeded PCG32: deterministic.

use std::f64::consts::PI;

use anyhow::{ensure, Result};
use glam::DVec3;

use super::{check_bands, eval_basis, ShCoeffs, Window, DEFAULT_BANDS, MAX_BANDS};
use crate::scene::hdr_image::HdrImage;

/// What to project and how to post-process it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Band count n in 1..=8 (n^2 coefficients); default 3.
    pub bands: usize,
    /// Rotation about +Y in radians, added to the azimuth exactly like
    /// env.glsl's `env_rotation`.
    pub rotation: f64,
    /// Radiance multiplier (env.glsl's `env_intensity`).
    pub intensity: f64,
    /// Window applied to the result; Hann by default, `Window::None` for the
    /// raw projection.
    pub window: Window,
}

impl Default for Projection {
    fn default() -> Self {
        Self { bands: DEFAULT_BANDS, rotation: 0.0, intensity: 1.0, window: Window::default() }
    }
}

/// Which integrator [`project`] uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Per-texel solid-angle quadrature ([`project_quadrature`]).
    Quadrature,
    /// Stratified jittered `n` x `n` Monte-Carlo ([`project_monte_carlo`]).
    MonteCarlo { n: u32, seed: u64 },
}

pub fn project(image: &HdrImage, p: &Projection, integrator: Integrator) -> Result<ShCoeffs> {
    match integrator {
        Integrator::Quadrature => project_quadrature(image, p),
        Integrator::MonteCarlo { n, seed } => project_monte_carlo(image, p, n, seed),
    }
}

/// env.glsl's `env_uv`, in f64: the map coordinates a direction reads.
/// `u` is not wrapped (it lies in [-0.5 + r/2pi, 1.5 + r/2pi]).
pub fn env_uv(dir: DVec3, rotation: f64) -> (f64, f64) {
    let phi = dir.x.atan2(-dir.z) + rotation;
    (phi / (2.0 * PI) + 0.5, dir.y.clamp(-1.0, 1.0).acos() / PI)
}

/// Unit direction for polar angle theta (from +Y) and SH azimuth phi
/// (atan2(d.x, -d.z)).
#[inline]
fn dir_from_angles(cos_t: f64, sin_t: f64, phi: f64) -> DVec3 {
    let (s, c) = phi.sin_cos();
    DVec3::new(sin_t * s, cos_t, -sin_t * c)
}

/// Direction through the centre of texel (x, y) of a `w` x `h` map drawn
/// with `rotation` (the inverse of [`env_uv`] at the centre).
pub fn texel_dir(x: u32, y: u32, w: u32, h: u32, rotation: f64) -> DVec3 {
    let theta = PI * (y as f64 + 0.5) / h as f64;
    let phi = 2.0 * PI * ((x as f64 + 0.5) / w as f64 - 0.5) - rotation;
    dir_from_angles(theta.cos(), theta.sin(), phi)
}

/// Exact solid angle of a texel in row `y`: (2pi / w)(cos theta_top - cos theta_bottom).
pub fn texel_solid_angle(y: u32, w: u32, h: u32) -> f64 {
    let top = (PI * y as f64 / h as f64).cos();
    let bottom = (PI * (y + 1) as f64 / h as f64).cos();
    2.0 * PI / w as f64 * (top - bottom)
}

fn check_image(image: &HdrImage, p: &Projection) -> Result<()> {
    check_bands(p.bands)?;
    ensure!(image.width > 0 && image.height > 0, "environment map is empty");
    ensure!(
        image.rgb.len() == 3 * image.width as usize * image.height as usize,
        "environment map holds {} floats, {}x{} RGB needs {}",
        image.rgb.len(),
        image.width,
        image.height,
        3 * image.width as usize * image.height as usize
    );
    ensure!(p.rotation.is_finite() && p.intensity.is_finite(), "rotation and intensity must be finite");
    Ok(())
}

/// Accumulates `weight * rgb * y` into `acc`.
#[inline]
fn accumulate(acc: &mut [[f64; 3]], y: &[f64], rgb: &[f32], weight: f64) {
    let l = [rgb[0] as f64 * weight, rgb[1] as f64 * weight, rgb[2] as f64 * weight];
    for (a, &yi) in acc.iter_mut().zip(y) {
        a[0] += l[0] * yi;
        a[1] += l[1] * yi;
        a[2] += l[2] * yi;
    }
}

fn finish(acc: Vec<[f64; 3]>, p: &Projection) -> Result<ShCoeffs> {
    Ok(ShCoeffs::from_coeffs(p.bands, acc)?.windowed(p.window))
}

/// Per-texel solid-angle quadrature (midpoint rule per texel, exact weights).
pub fn project_quadrature(image: &HdrImage, p: &Projection) -> Result<ShCoeffs> {
    check_image(image, p)?;
    let (w, h) = (image.width, image.height);
    let nc = p.bands * p.bands;
    let mut acc = vec![[0.0; 3]; nc];
    let mut y = [0.0; MAX_BANDS * MAX_BANDS];
    let y = &mut y[..nc];
    let phis: Vec<f64> =
        (0..w).map(|x| 2.0 * PI * ((x as f64 + 0.5) / w as f64 - 0.5) - p.rotation).collect();
    for row in 0..h {
        let theta = PI * (row as f64 + 0.5) / h as f64;
        let (sin_t, cos_t) = theta.sin_cos();
        let weight = texel_solid_angle(row, w, h) * p.intensity;
        let texels = &image.rgb[3 * (row * w) as usize..3 * ((row + 1) * w) as usize];
        for (rgb, &phi) in texels.chunks_exact(3).zip(&phis) {
            eval_basis(p.bands, dir_from_angles(cos_t, sin_t, phi), y);
            accumulate(&mut acc, y, rgb, weight);
        }
    }
    finish(acc, p)
}

/// Monte-Carlo projection over an `n` x `n` stratified jittered grid
/// (n^2 samples, weight 4pi / n^2 each, nearest-texel lookup), seeded.
pub fn project_monte_carlo(image: &HdrImage, p: &Projection, n: u32, seed: u64) -> Result<ShCoeffs> {
    check_image(image, p)?;
    ensure!(n > 0, "Monte-Carlo projection needs n >= 1");
    let (w, h) = (image.width as usize, image.height as usize);
    let nc = p.bands * p.bands;
    let mut acc = vec![[0.0; 3]; nc];
    let mut y = [0.0; MAX_BANDS * MAX_BANDS];
    let y = &mut y[..nc];
    let mut rng = Pcg32::new(seed, 0xda3e_39cb_94b9_5bdb);
    let weight = 4.0 * PI / (n as f64 * n as f64) * p.intensity;
    for i in 0..n {
        for j in 0..n {
            let xi1 = (i as f64 + rng.next_f64()) / n as f64;
            let xi2 = (j as f64 + rng.next_f64()) / n as f64;
            let cos_t = 1.0 - 2.0 * xi1;
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let phi = 2.0 * PI * xi2;
            // Nearest texel, as env.glsl addresses it.
            let u = (phi + p.rotation) / (2.0 * PI) + 0.5;
            let u = u - u.floor();
            let v = cos_t.clamp(-1.0, 1.0).acos() / PI;
            let tx = ((u * w as f64) as usize).min(w - 1);
            let ty = ((v * h as f64) as usize).min(h - 1);
            let t = 3 * (ty * w + tx);
            eval_basis(p.bands, dir_from_angles(cos_t, sin_t, phi), y);
            accumulate(&mut acc, y, &image.rgb[t..t + 3], weight);
        }
    }
    finish(acc, p)
}

/// PCG32 (O'Neill, pcg32_random_r): a small, seeded, deterministic generator.
pub(super) struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    pub(super) fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self { state: 0, inc: (stream << 1) | 1 };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    pub(super) fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1) with 32 bits of resolution.
    pub(super) fn next_f64(&mut self) -> f64 {
        self.next_u32() as f64 * (1.0 / 4_294_967_296.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_dir_inverts_env_uv() {
        let (w, h) = (64u32, 32u32);
        for rotation in [0.0, 0.7, -2.5] {
            for (x, y) in [(0, 0), (31, 16), (32, 5), (63, 31), (48, 16), (16, 16)] {
                let (u, v) = env_uv(texel_dir(x, y, w, h, rotation), rotation);
                let u = u - u.floor();
                assert!((u - (x as f64 + 0.5) / w as f64).abs() < 1e-12, "u {u} at {x},{y} rot {rotation}");
                assert!((v - (y as f64 + 0.5) / h as f64).abs() < 1e-12);
            }
        }
        // The documented landmarks: centre column -Z, u = 0.75 +X, top row +Y.
        assert!(texel_dir(32, 16, 64, 32, 0.0).z < -0.99);
        let (u, v) = env_uv(DVec3::X, 0.0);
        assert!((u - 0.75).abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
        assert!(texel_dir(5, 0, 64, 32, 0.0).y > 0.99);
    }

    #[test]
    fn solid_angles_sum_to_4pi() {
        for (w, h) in [(1u32, 1u32), (3, 7), (1024, 512), (128, 64)] {
            let total: f64 = (0..h).map(|y| texel_solid_angle(y, w, h) * w as f64).sum();
            assert!((total - 4.0 * PI).abs() < 1e-12, "{w}x{h}: {total}");
        }
    }

    #[test]
    fn pcg32_reference_and_uniformity() {
        // pcg32-global demo, seed 42 stream 54: first outputs.
        let mut r = Pcg32::new(42, 54);
        let got: Vec<u32> = (0..3).map(|_| r.next_u32()).collect();
        assert_eq!(got, [0xa15c02b7, 0x7b47f409, 0xba1d3330]);
        let mut r = Pcg32::new(1, 2);
        let mean = (0..100_000).map(|_| r.next_f64()).sum::<f64>() / 100_000.0;
        assert!((mean - 0.5).abs() < 5e-3);
    }

    #[test]
    fn image_validation() {
        let bad = HdrImage { width: 4, height: 2, rgb: vec![1.0; 23] };
        assert!(project_quadrature(&bad, &Projection::default()).is_err());
        let empty = HdrImage { width: 0, height: 2, rgb: vec![] };
        assert!(project_monte_carlo(&empty, &Projection::default(), 4, 0).is_err());
        let ok = HdrImage { width: 4, height: 2, rgb: vec![1.0; 24] };
        assert!(project_monte_carlo(&ok, &Projection::default(), 0, 0).is_err());
    }
}
