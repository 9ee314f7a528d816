//! Irradiance: convolution of radiance with the clamped cosine max(0, n·w)
//! (Ramamoorthi & Hanrahan, "An Efficient Representation for Irradiance
//! Environment Maps", 2001).
//!
//! By Funk-Hecke, ∫ K(n·w) y_lm(w) dw = Λ_l y_lm(n) with
//! Λ_l = 2pi ∫_{-1}^{1} K(t) P_l(t) dt, so for K(t) = max(0, t)
//! E_lm = Â_l L_lm with Â_0 = pi, Â_1 = 2pi/3, Â_l = 0 for odd l > 1 and, for
//! even l >= 2,
//! Â_l = 2pi (-1)^(l/2 - 1) / ((l + 2)(l - 1)) · l! / (2^l ((l/2)!)^2)
//! (Â_2 = pi/4, Â_4 = -pi/24, Â_6 = pi/64). No 1/pi anywhere: E is
//! irradiance; the radiance leaving a Lambertian surface of albedo a is
//! a · E / pi. The same identity gives the projection of a clamped-cosine
//! lobe max(0, a·w): its coefficients are Â_l y_lm(a).

use std::f64::consts::PI;

use super::basis::band_of;
use super::ShCoeffs;

/// Â_l, the SH coefficient (Funk-Hecke eigenvalue) of the clamped cosine.
pub fn clamped_cosine_a_hat(l: usize) -> f64 {
    match l {
        0 => PI,
        1 => 2.0 * PI / 3.0,
        _ if !l.is_multiple_of(2) => 0.0,
        _ => {
            let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
            let sign = if (l / 2 - 1).is_multiple_of(2) { 1.0 } else { -1.0 };
            2.0 * PI * sign / ((l + 2) as f64 * (l - 1) as f64) * fact(l)
                / (2f64.powi(l as i32) * fact(l / 2).powi(2))
        }
    }
}

impl ShCoeffs {
    /// Irradiance coefficients E_lm = Â_l L_lm: `eval(n)` of the result is
    /// E(n) = ∫ L(w) max(0, n·w) dw (not divided by pi; a Lambertian surface
    /// of albedo a exits a · E(n) / pi). Apply a window before or after, not
    /// both (the operations commute).
    pub fn irradiance(&self) -> ShCoeffs {
        let mut out = self.clone();
        for (i, c) in out.rgb.iter_mut().enumerate() {
            let a = clamped_cosine_a_hat(band_of(i));
            c.iter_mut().for_each(|v| *v *= a);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hat_values() {
        let want = [PI, 2.0 * PI / 3.0, PI / 4.0, 0.0, -PI / 24.0, 0.0, PI / 64.0, 0.0];
        for (l, w) in want.iter().enumerate() {
            let got = clamped_cosine_a_hat(l);
            assert!((got - w).abs() < 1e-14, "Â_{l} = {got}, want {w}");
        }
    }

    /// Λ_l = 2pi ∫_0^1 t P_l(t) dt by quadrature agrees with the closed form
    /// (catches a formula that happens to hit the tabulated values).
    #[test]
    fn a_hat_matches_funk_hecke_integral() {
        let n = 20_000;
        for l in 0..8usize {
            let mut s = 0.0;
            for i in 0..n {
                let t = (i as f64 + 0.5) / n as f64;
                // Legendre P_l(t) by Bonnet's recurrence.
                let (mut p0, mut p1) = (1.0, t);
                let p = if l == 0 {
                    1.0
                } else {
                    for k in 1..l {
                        (p0, p1) = (p1, ((2 * k + 1) as f64 * t * p1 - k as f64 * p0) / (k + 1) as f64);
                    }
                    p1
                };
                s += t * p / n as f64;
            }
            let lambda = 2.0 * PI * s;
            assert!((lambda - clamped_cosine_a_hat(l)).abs() < 1e-7, "l {l}: {lambda}");
        }
    }

    #[test]
    fn irradiance_scales_bands() {
        let c = ShCoeffs::from_coeffs(3, vec![[1.0, 1.0, 1.0]; 9]).unwrap();
        let e = c.irradiance();
        assert!((e.coeffs()[0][0] - PI).abs() < 1e-15);
        assert!((e.coeffs()[2][1] - 2.0 * PI / 3.0).abs() < 1e-15);
        assert!((e.coeffs()[6][2] - PI / 4.0).abs() < 1e-15);
    }
}
