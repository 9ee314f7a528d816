//! Rotation of the environment about +Y, applied to the coefficients.
//!
//! env.glsl reads direction d at azimuth phi(d) + rotation, where
//! phi = atan2(d.x, -d.z) is also the SH azimuth (see `basis`). So with
//! `rotation` increased by r the radiance is L_r(theta, phi) =
//! L(theta, phi + r), and
//!
//! ```text
//! L_r,lm = ∫ L(theta, psi) y_lm(theta, psi - r) dw
//! ```
//!
//! With y_l,m ~ cos(m phi) and y_l,-m ~ sin(m phi) (m > 0), expanding
//! cos(m psi - m r) and sin(m psi - m r):
//!
//! ```text
//! L_r,l,m  = L_l,m  cos(m r) + L_l,-m sin(m r)
//! L_r,l,-m = L_l,-m cos(m r) - L_l,m  sin(m r)
//! ```
//!
//! Geometrically, increasing env.glsl's rotation by r turns the environment
//! by the right-handed rotation R_y(r) (glam's `from_rotation_y`): what was
//! seen in direction d is now seen in R_y(r) d (+X goes to -Z for r = pi/2).

use super::{sh_index, ShCoeffs};

impl ShCoeffs {
    /// The coefficients of this environment with `angle` (radians) added to
    /// its env.glsl rotation, i.e. turned by R_y(angle). Exact (no
    /// re-projection), O(n^2).
    pub fn rotated_y(&self, angle: f64) -> ShCoeffs {
        let mut out = self.clone();
        for l in 1..self.bands {
            for m in 1..=l as i32 {
                let (s, c) = (m as f64 * angle).sin_cos();
                let (ip, im) = (sh_index(l, m), sh_index(l, -m));
                let (a, b) = (self.rgb[ip], self.rgb[im]);
                for k in 0..3 {
                    out.rgb[ip][k] = a[k] * c + b[k] * s;
                    out.rgb[im][k] = b[k] * c - a[k] * s;
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use glam::{DQuat, DVec3};

    use super::*;
    use crate::scene::sh::fibonacci_sphere;
    use crate::scene::sh::project::Pcg32;

    fn random_coeffs(bands: usize, seed: u64) -> ShCoeffs {
        let mut rng = Pcg32::new(seed, 7);
        let rgb = (0..bands * bands).map(|_| [0; 3].map(|_: i32| rng.next_f64() * 2.0 - 1.0)).collect();
        ShCoeffs::from_coeffs(bands, rgb).unwrap()
    }

    /// f_r(R_y(r) d) = f(d) for every d: the rotation is the documented
    /// right-handed turn, for every band.
    #[test]
    fn rotation_moves_the_function_by_r_y() {
        let c = random_coeffs(8, 3);
        for angle in [0.3, -1.1, 2.0, std::f64::consts::PI] {
            let r = c.rotated_y(angle);
            let q = DQuat::from_rotation_y(angle);
            for d in fibonacci_sphere(300) {
                let (a, b) = (c.eval(d), r.eval(q * d));
                for k in 0..3 {
                    assert!((a[k] - b[k]).abs() < 1e-10, "angle {angle}, d {d}: {a:?} vs {b:?}");
                }
            }
        }
        // Composition and inverse.
        let back = c.rotated_y(0.8).rotated_y(-0.8);
        let twice = c.rotated_y(0.5).rotated_y(0.5);
        let once = c.rotated_y(1.0);
        for i in 0..64 {
            for k in 0..3 {
                assert!((back.coeffs()[i][k] - c.coeffs()[i][k]).abs() < 1e-12);
                assert!((twice.coeffs()[i][k] - once.coeffs()[i][k]).abs() < 1e-12);
            }
        }
        // +X -> -Z for a quarter turn.
        let q = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
        assert!((q * DVec3::X - DVec3::NEG_Z).length() < 1e-12);
    }
}
