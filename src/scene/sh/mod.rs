//! Spherical-harmonic (SH) core for image-based lighting from equirectangular
//! HDR environment maps, on the CPU, in f64.
//!
//! - `basis`: the real SH basis y_l^m for bands n = 1..=8 (l < n) and its
//!   frame (polar angle from +Y, env.glsl's azimuth atan2(d.x, -d.z)).
//! - `project`: projection of an [`HdrImage`] with two integrators, per-texel
//!   solid-angle quadrature and stratified jittered Monte-Carlo.
//! - `window`: Hann / Lanczos windowing against ringing (Hann by default).
//! - `irradiance`: convolution with the clamped cosine (Â_l).
//! - `rotate`: the environment rotation about +Y applied to coefficients.
//!
//! Units: a projection of radiance L gives radiance coefficients L_lm, and
//! [`ShCoeffs::eval`] reconstructs radiance. [`ShCoeffs::irradiance`] gives
//! the coefficients of the irradiance E(n) = ∫ L(w) max(0, n·w) dw; a
//! Lambertian surface of albedo a then exits radiance a · E / π.

mod basis;
mod irradiance;
mod project;
mod rotate;
#[cfg(test)]
mod tests_hdri;
#[cfg(test)]
mod tests_maps;
mod window;

use anyhow::{ensure, Result};
use glam::DVec3;

pub use basis::{band_of, eval_basis, sh_index, DEFAULT_BANDS, MAX_BANDS};
pub use irradiance::clamped_cosine_a_hat;
pub use project::{
    env_uv, project, project_monte_carlo, project_quadrature, texel_dir, texel_solid_angle, Integrator,
    Projection,
};
pub use window::Window;

#[cfg(doc)]
use super::hdr_image::HdrImage;

/// SH coefficients of an RGB function on the sphere: `bands`^2 entries,
/// coefficient (l, m) at [`sh_index`]`(l, m)`.
#[derive(Clone, Debug, PartialEq)]
pub struct ShCoeffs {
    bands: usize,
    rgb: Vec<[f64; 3]>,
}

/// Errors unless `bands` is in 1..=[`MAX_BANDS`].
pub fn check_bands(bands: usize) -> Result<()> {
    ensure!((1..=MAX_BANDS).contains(&bands), "SH band count must be in 1..={MAX_BANDS} (got {bands})");
    Ok(())
}

impl ShCoeffs {
    /// All-zero coefficients.
    pub fn zero(bands: usize) -> Result<Self> {
        check_bands(bands)?;
        Ok(Self { bands, rgb: vec![[0.0; 3]; bands * bands] })
    }

    /// Wraps `rgb`, which must hold exactly `bands`^2 entries.
    pub fn from_coeffs(bands: usize, rgb: Vec<[f64; 3]>) -> Result<Self> {
        check_bands(bands)?;
        ensure!(
            rgb.len() == bands * bands,
            "{bands} SH bands need {} coefficients (got {})",
            bands * bands,
            rgb.len()
        );
        Ok(Self { bands, rgb })
    }

    pub fn bands(&self) -> usize {
        self.bands
    }

    pub fn coeffs(&self) -> &[[f64; 3]] {
        &self.rgb
    }

    /// Reconstruction sum_lm c_lm y_lm(dir); `dir` is normalised here.
    pub fn eval(&self, dir: DVec3) -> [f64; 3] {
        let mut y = [0.0; MAX_BANDS * MAX_BANDS];
        eval_basis(self.bands, dir.normalize(), &mut y);
        let mut out = [0.0; 3];
        for (c, yi) in self.rgb.iter().zip(y) {
            for k in 0..3 {
                out[k] += c[k] * yi;
            }
        }
        out
    }
}

/// `n` nearly uniform unit directions (Fibonacci / golden-angle spiral), for
/// dense checks over the sphere.
pub fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let a = golden * i as f64;
            DVec3::new(r * a.cos(), y, r * a.sin())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_validation() {
        assert!(check_bands(0).is_err());
        assert!(check_bands(9).is_err());
        assert!(ShCoeffs::zero(0).is_err());
        assert!(ShCoeffs::zero(9).is_err());
        for n in 1..=8 {
            assert_eq!(ShCoeffs::zero(n).unwrap().coeffs().len(), n * n);
        }
        assert!(ShCoeffs::from_coeffs(3, vec![[0.0; 3]; 8]).is_err());
        let img = crate::scene::HdrImage { width: 4, height: 2, rgb: vec![1.0; 24] };
        for bands in [0, 9] {
            let p = Projection { bands, ..Default::default() };
            assert!(project_quadrature(&img, &p).is_err());
            assert!(project_monte_carlo(&img, &p, 4, 1).is_err());
        }
    }

    #[test]
    fn fibonacci_points_are_unit_and_balanced() {
        let pts = fibonacci_sphere(10_000);
        let mean = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        assert!(pts.iter().all(|p| (p.length() - 1.0).abs() < 1e-12));
        assert!(mean.length() < 1e-3, "{mean}");
    }
}
