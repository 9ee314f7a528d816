//! The environment's diffuse light as SH irradiance: projected once on the CPU at upload (scene/sh,
//! 3 bands, Hann window); each frame the coefficients are rotated (exact, no re-projection), scaled by
//! intensity and convolved with the clamped cosine for glsl/common/env.glsl `sh_irradiance`.

use anyhow::Result;

use super::shared::SH_IRRADIANCE_COEFFS;
use crate::scene::sh::{project_quadrature, Projection, ShCoeffs, Window};
use crate::scene::{Environment, HdrImage};

/// Bands the shaders evaluate (SH_IRRADIANCE_COEFFS = bands²).
pub const SH_BANDS: usize = 3;
const _: () = assert!(SH_BANDS * SH_BANDS == SH_IRRADIANCE_COEFFS as usize);

/// Radiance coefficients of `map` as stored on the GPU (rotation 0,
/// intensity 1, Hann-windowed). Logs the projection time.
pub fn project_environment(map: &HdrImage) -> Result<ShCoeffs> {
    let t = std::time::Instant::now();
    let p = Projection { bands: SH_BANDS, ..Default::default() };
    let sh = project_quadrature(map, &p)?;
    log::info!(
        "environment SH: {}x{} map projected to {SH_BANDS} bands (quadrature, Hann window) in {:.1} ms",
        map.width,
        map.height,
        t.elapsed().as_secs_f64() * 1e3
    );
    Ok(sh)
}

/// The frame's irradiance coefficients E_lm (rgb, w = 0) for `env`, whose
/// map projected to `radiance` (Hann-windowed); `truncated` undoes the window: plain L2 irradiance is
/// within 1.8-2.6 % of brute force on the shipped maps where Hann's is 9-25 % off (scene/sh/window.rs),
/// at the price of ringing that can dip below zero (env.glsl clamps it).
pub fn irradiance_uniform(
    radiance: &ShCoeffs,
    env: &Environment,
    truncated: bool,
) -> [[f32; 4]; SH_IRRADIANCE_COEFFS as usize] {
    let radiance = if truncated { radiance.unwindowed(Window::Hann) } else { radiance.clone() };
    let e = radiance.rotated_y(env.rotation as f64).irradiance();
    let scale = env.intensity as f64;
    let mut out = [[0.0f32; 4]; SH_IRRADIANCE_COEFFS as usize];
    for (o, c) in out.iter_mut().zip(e.coeffs()) {
        *o = [(c[0] * scale) as f32, (c[1] * scale) as f32, (c[2] * scale) as f32, 0.0];
    }
    out
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use glam::DVec3;

    use super::*;
    use crate::scene::sh::{eval_basis, fibonacci_sphere};

    /// The shaders' evaluation, in f64 from the f32 uniform.
    fn eval(u: &[[f32; 4]; 9], n: DVec3) -> [f64; 3] {
        let mut y = [0.0; 9];
        eval_basis(3, n, &mut y);
        let mut e = [0.0; 3];
        for (c, yi) in u.iter().zip(y) {
            for k in 0..3 {
                e[k] += c[k] as f64 * yi;
            }
        }
        e
    }

    /// A constant map of radiance L gives E = pi L at every normal, so
    /// E / pi equals the constant ambient (the map's mean), up to the
    /// midpoint rule's O(1/h^2) leak into bands 1-2 (~1e-5 at 128 rows).
    #[test]
    fn constant_map_gives_pi_l() {
        let l = [0.25f32, 1.5, 3.0];
        let map = HdrImage { width: 256, height: 128, rgb: l.repeat(256 * 128) };
        let sh = project_environment(&map).unwrap();
        let env = Environment { intensity: 2.0, rotation: 1.3, ..Default::default() };
        let u = irradiance_uniform(&sh, &env, false);
        for n in fibonacci_sphere(200) {
            let e = eval(&u, n);
            for k in 0..3 {
                let want = PI * l[k] as f64 * 2.0;
                assert!((e[k] - want).abs() < 5e-5 * want, "n {n}: {e:?}");
            }
        }
    }

    /// A map lit only on the +X hemisphere: the uniform's irradiance is
    /// larger at +X than at -X, and a quarter turn (+X -> -Z) moves it.
    #[test]
    fn hemisphere_map_direction_and_rotation() {
        let (w, h) = (64u32, 32u32);
        let mut rgb = vec![0.0f32; (w * h * 3) as usize];
        for y in 0..h {
            for x in 0..w {
                if crate::scene::sh::texel_dir(x, y, w, h, 0.0).x > 0.0 {
                    rgb[((y * w + x) * 3) as usize..][..3].copy_from_slice(&[1.0; 3]);
                }
            }
        }
        let sh = project_environment(&HdrImage { width: w, height: h, rgb }).unwrap();
        let u = irradiance_uniform(&sh, &Environment::default(), false);
        assert!(eval(&u, DVec3::X)[0] > 2.0 && eval(&u, DVec3::NEG_X)[0] < 0.5);
        let r = Environment { rotation: std::f32::consts::FRAC_PI_2, ..Default::default() };
        let u = irradiance_uniform(&sh, &r, false);
        assert!(eval(&u, DVec3::NEG_Z)[0] > 2.0 && eval(&u, DVec3::X)[0] < 1.6);
        assert!((eval(&u, DVec3::X)[0] - eval(&u, DVec3::NEG_X)[0]).abs() < 1e-4);
        // A lit half space gives E = pi (1 + cos) / 2, bands 0 and 1 only, so the plain truncation is
        // exact and Hann's 0.75 on band 1 takes an eighth off the bright side: pi 0.875.
        let exact = irradiance_uniform(&sh, &Environment::default(), true);
        for (n, want) in [(DVec3::X, PI), (DVec3::NEG_X, 0.0), (DVec3::Y, PI / 2.0)] {
            assert!((eval(&exact, n)[0] - want).abs() < 0.01 * PI, "{n}: {:?}", eval(&exact, n));
        }
        let hann = irradiance_uniform(&sh, &Environment::default(), false);
        assert!((eval(&hann, DVec3::X)[0] - 0.875 * PI).abs() < 0.01 * PI);
    }
}
