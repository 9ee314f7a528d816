//! Real spherical-harmonic basis y_l^m, l = 0..7, orthonormal over the sphere.
//!
//! Convention (Green, "Spherical Harmonic Lighting: The Gritty Details", and
//! Sloan, "Stupid Spherical Harmonics Tricks", Condon-Shortley phase kept):
//!
//! ```text
//! y_l^m  = sqrt(2) K_l^m cos( m phi) P_l^m(cos theta)   m > 0
//! y_l^0  =         K_l^0             P_l^0(cos theta)
//! y_l^-m = sqrt(2) K_l^m sin( m phi) P_l^m(cos theta)   m > 0
//! K_l^m  = sqrt((2l + 1) / (4 pi) * (l - m)! / (l + m)!)
//! ```
//!
//! with P_l^m from the standard recurrence (P_m^m = (-1)^m (2m - 1)!! (1 -
//! x^2)^(m/2), then upwards in l). Coefficient (l, m) is stored at index
//! `l (l + 1) + m`.
//!
//! Frame, in the renderer's +Y-up world: the polar angle is measured from +Y
//! (cos theta = d.y) and the azimuth is env.glsl's, before the map rotation:
//! phi = atan2(d.x, -d.z), so phi = 0 looks down -Z (the map's centre column,
//! u = 0.5) and phi = pi/2 looks down +X (u = 0.75). In the usual (x, y, z)
//! notation of SH tables that means x_sh = sin theta cos phi = -d.z,
//! y_sh = sin theta sin phi = d.x, z_sh = d.y. (That frame is left-handed;
//! the basis is orthonormal all the same, and the only thing the handedness
//! decides is the sign of an azimuthal rotation, which `rotate.rs` derives.)
//! So, for example, y_1^-1 = -sqrt(3/4pi) d.x, y_1^0 = sqrt(3/4pi) d.y,
//! y_1^1 = sqrt(3/4pi) d.z.
//!
//! The azimuthal factors are evaluated without trigonometry as
//! sin^m(theta) e^{i m phi} = (x_sh + i y_sh)^m, with the sin^m(theta) taken
//! out of P_l^m, which also keeps the poles exact.

use std::sync::OnceLock;

use glam::DVec3;

/// Largest supported band count n (coefficients n^2, degrees l < n).
pub const MAX_BANDS: usize = 8;
/// Band count used unless asked otherwise (L2: 9 coefficients).
pub const DEFAULT_BANDS: usize = 3;

/// Index of coefficient (l, m), |m| <= l.
#[inline]
pub const fn sh_index(l: usize, m: i32) -> usize {
    ((l * (l + 1)) as isize + m as isize) as usize
}

/// Degree l of the coefficient stored at `index`.
#[inline]
pub fn band_of(index: usize) -> usize {
    let mut l = 0;
    while (l + 1) * (l + 1) <= index {
        l += 1;
    }
    l
}

/// K_l^m, with the sqrt(2) of the m != 0 functions folded in.
fn norm_table() -> &'static [[f64; MAX_BANDS]; MAX_BANDS] {
    static TABLE: OnceLock<[[f64; MAX_BANDS]; MAX_BANDS]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
        let mut t = [[0.0; MAX_BANDS]; MAX_BANDS];
        for (l, row) in t.iter_mut().enumerate() {
            for (m, k) in row.iter_mut().enumerate().take(l + 1) {
                let kk =
                    ((2 * l + 1) as f64 / (4.0 * std::f64::consts::PI) * fact(l - m) / fact(l + m)).sqrt();
                *k = if m == 0 { kk } else { std::f64::consts::SQRT_2 * kk };
            }
        }
        t
    })
}

/// Evaluates the first `bands`^2 basis functions at the unit direction `dir`
/// (renderer frame, not normalised here) into `out[..bands * bands]`.
///
/// Panics if `bands` is not in 1..=[`MAX_BANDS`] or `out` is too short; this
/// is the inner loop of the projections, which validate `bands` once.
pub fn eval_basis(bands: usize, dir: DVec3, out: &mut [f64]) {
    assert!((1..=MAX_BANDS).contains(&bands), "SH band count {bands} not in 1..={MAX_BANDS}");
    assert!(out.len() >= bands * bands, "SH output slice too short");
    let k = norm_table();
    let (x, y, z) = (-dir.z, dir.x, dir.y);
    // (cm, sm) = (x + i y)^m = sin^m(theta) (cos m phi, sin m phi).
    let (mut cm, mut sm) = (1.0f64, 0.0f64);
    // P_m^m / sin^m(theta) = (-1)^m (2m - 1)!!
    let mut pmm = 1.0f64;
    for m in 0..bands {
        if m > 0 {
            pmm *= -((2 * m - 1) as f64);
        }
        let (mut p_prev, mut p) = (0.0f64, pmm);
        for l in m..bands {
            if l == m + 1 {
                (p_prev, p) = (p, z * (2 * m + 1) as f64 * pmm);
            } else if l > m + 1 {
                let next = ((2 * l - 1) as f64 * z * p - (l + m - 1) as f64 * p_prev) / (l - m) as f64;
                (p_prev, p) = (p, next);
            }
            let kp = k[l][m] * p;
            if m == 0 {
                out[sh_index(l, 0)] = kp;
            } else {
                out[sh_index(l, m as i32)] = kp * cm;
                out[sh_index(l, -(m as i32))] = kp * sm;
            }
        }
        (cm, sm) = (cm * x - sm * y, cm * y + sm * x);
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    /// The first nine functions written out (Sloan's table, CS phase), in the
    /// SH frame x = -d.z, y = d.x, z = d.y.
    fn closed_form_l2(d: DVec3) -> [f64; 9] {
        let (x, y, z) = (-d.z, d.x, d.y);
        let c1 = (3.0 / (4.0 * PI)).sqrt();
        let c2 = 0.5 * (15.0 / PI).sqrt();
        [
            0.5 / PI.sqrt(),
            -c1 * y,
            c1 * z,
            -c1 * x,
            c2 * x * y,
            -c2 * y * z,
            0.25 * (5.0 / PI).sqrt() * (3.0 * z * z - 1.0),
            -c2 * x * z,
            0.25 * (15.0 / PI).sqrt() * (x * x - y * y),
        ]
    }

    fn test_dirs() -> Vec<DVec3> {
        let mut dirs = vec![DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
        dirs.extend(super::super::fibonacci_sphere(200));
        dirs
    }

    #[test]
    fn recurrence_matches_closed_forms_l2() {
        let mut out = [0.0; 64];
        for d in test_dirs() {
            for bands in 3..=MAX_BANDS {
                eval_basis(bands, d, &mut out);
                let want = closed_form_l2(d);
                for i in 0..9 {
                    assert!((out[i] - want[i]).abs() < 1e-12, "y[{i}]({d}) = {} want {}", out[i], want[i]);
                }
            }
        }
    }

    #[test]
    fn l1_in_renderer_axes() {
        // The documented axis table: y_1^-1 ~ -x, y_1^0 ~ +y, y_1^1 ~ +z.
        let c1 = (3.0 / (4.0 * PI)).sqrt();
        let mut out = [0.0; 4];
        eval_basis(2, DVec3::X, &mut out);
        assert!((out[1] + c1).abs() < 1e-12 && out[2].abs() < 1e-12 && out[3].abs() < 1e-12);
        eval_basis(2, DVec3::Y, &mut out);
        assert!(out[1].abs() < 1e-12 && (out[2] - c1).abs() < 1e-12 && out[3].abs() < 1e-12);
        eval_basis(2, DVec3::Z, &mut out);
        assert!(out[1].abs() < 1e-12 && out[2].abs() < 1e-12 && (out[3] - c1).abs() < 1e-12);
    }

    #[test]
    fn orthonormal_over_the_sphere() {
        // Gauss-Legendre would be exact; a fine midpoint grid in (cos theta,
        // phi) is exact in phi for |m| < 2 * 64 and O(1/n^2) in cos theta.
        let (nz, nphi) = (400usize, 64usize);
        let n = MAX_BANDS * MAX_BANDS;
        let mut gram = vec![0.0f64; n * n];
        let mut y = [0.0; 64];
        let w = 4.0 * PI / (nz * nphi) as f64;
        for i in 0..nz {
            let ct = 1.0 - 2.0 * (i as f64 + 0.5) / nz as f64;
            let st = (1.0 - ct * ct).sqrt();
            for j in 0..nphi {
                let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
                eval_basis(MAX_BANDS, DVec3::new(st * phi.sin(), ct, -st * phi.cos()), &mut y);
                for a in 0..n {
                    for b in 0..n {
                        gram[a * n + b] += w * y[a] * y[b];
                    }
                }
            }
        }
        let mut worst = 0.0f64;
        for a in 0..n {
            for b in 0..n {
                let want = if a == b { 1.0 } else { 0.0 };
                worst = worst.max((gram[a * n + b] - want).abs());
            }
        }
        println!("orthonormality: max |<y_a, y_b> - delta_ab| = {worst:.2e} (64 functions)");
        assert!(worst < 2e-3, "basis not orthonormal: {worst}");
    }

    #[test]
    fn index_helpers() {
        assert_eq!(sh_index(0, 0), 0);
        assert_eq!(sh_index(1, -1), 1);
        assert_eq!(sh_index(2, 2), 8);
        assert_eq!(sh_index(7, 7), 63);
        for i in 0..64 {
            let l = band_of(i);
            assert!(l * l <= i && i < (l + 1) * (l + 1));
        }
    }
}
