//! Tests of the whole pipeline on synthetic maps (constant, clamped-cosine
//! lobe, single-axis lights, a sun): projection, windowing, irradiance.
//! The shipped-HDR tests are in `tests_hdri`.

use std::f64::consts::PI;

use glam::DVec3;

use super::*;
use crate::scene::HdrImage;

/// A `w` x `h` map whose texel (x, y) holds f(centre direction of the texel).
pub(super) fn map_from_fn(w: u32, h: u32, f: impl Fn(DVec3) -> [f32; 3]) -> HdrImage {
    let mut rgb = Vec::with_capacity(3 * (w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            rgb.extend(f(texel_dir(x, y, w, h, 0.0)));
        }
    }
    HdrImage { width: w, height: h, rgb }
}

/// A map that is `inside` where the texel centre's (u, v) lies in the given
/// ranges (u wrapped) and 0 elsewhere: built from env.glsl's (u, v) only, so
/// it does not depend on this module's direction mapping.
fn map_from_uv(w: u32, h: u32, inside: impl Fn(f64, f64) -> bool) -> HdrImage {
    let mut rgb = Vec::with_capacity(3 * (w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = ((x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64);
            rgb.extend([if inside(u, v) { 1.0f32 } else { 0.0 }; 3]);
        }
    }
    HdrImage { width: w, height: h, rgb }
}

pub(super) fn raw(bands: usize) -> Projection {
    Projection { bands, window: Window::None, ..Default::default() }
}

fn max_abs_from(c: &ShCoeffs, first: usize) -> f64 {
    c.coeffs()[first..].iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))
}

#[test]
fn constant_map_both_integrators_every_band_count() {
    let c = 0.7f32;
    let img = HdrImage { width: 512, height: 256, rgb: vec![c; 3 * 512 * 256] };
    let want00 = c as f64 * 2.0 * PI.sqrt();
    for bands in 1..=MAX_BANDS {
        for (name, integ, tol_rest) in [
            // Midpoint rule in theta: the zonal terms (m = 0) carry an
            // O((pi / h)^2 l^2) error (measured 8e-5 c at 8 bands, h = 256).
            ("quadrature", Integrator::Quadrature, 2e-4),
            // 64^2 jittered strata: the weights still sum to 4pi exactly, so
            // L00 is exact; the rest is noise (measured 2.5e-2 c at 8 bands).
            ("monte-carlo", Integrator::MonteCarlo { n: 64, seed: 9 }, 5e-2),
        ] {
            let sh = project(&img, &raw(bands), integ).unwrap();
            for k in 0..3 {
                let e = (sh.coeffs()[0][k] - want00).abs();
                assert!(e < 1e-9, "{name} bands {bands}: L00 = {} want {want00}", sh.coeffs()[0][k]);
            }
            let rest = if bands > 1 { max_abs_from(&sh, 1) } else { 0.0 };
            if bands >= 3 {
                println!("constant {c}: {name}, {bands} bands: max |L_lm|, l > 0 = {rest:.2e}");
            }
            assert!(rest < tol_rest * c as f64, "{name} bands {bands}: non-constant terms {rest}");
            // Irradiance pi c everywhere (the window keeps band 0).
            let e = project(&img, &Projection { bands, ..Default::default() }, integ).unwrap().irradiance();
            for d in fibonacci_sphere(50) {
                let v = e.eval(d);
                for vk in v {
                    assert!(
                        (vk - PI * c as f64).abs() < 1e-2 * c as f64,
                        "{name} bands {bands}: E({d}) = {v:?}"
                    );
                }
            }
        }
    }
}

/// max(0, a·w) projects to Â_l y_lm(a) (Funk-Hecke). Written out for l <= 2
/// with a = (ax, ay, az) in the renderer frame:
/// L00 = sqrt(pi)/2; (L1-1, L10, L11) = sqrt(pi/3) (-ax, ay, az);
/// L2-2 = -s ax az, L2-1 = -s ax ay, L20 = sqrt(5 pi)/16 (3 ay^2 - 1),
/// L21 = s ay az, L22 = s/2 (az^2 - ax^2), s = sqrt(15 pi)/8.
#[test]
fn clamped_cosine_lobe_matches_closed_form() {
    let a = DVec3::new(0.3, 0.5, -0.8).normalize();
    let img = map_from_fn(1024, 512, |d| [d.dot(a).max(0.0) as f32; 3]);
    let s = (15.0 * PI).sqrt() / 8.0;
    let by_hand = [
        PI.sqrt() / 2.0,
        -(PI / 3.0).sqrt() * a.x,
        (PI / 3.0).sqrt() * a.y,
        (PI / 3.0).sqrt() * a.z,
        -s * a.x * a.z,
        -s * a.x * a.y,
        (5.0 * PI).sqrt() / 16.0 * (3.0 * a.y * a.y - 1.0),
        s * a.y * a.z,
        s / 2.0 * (a.z * a.z - a.x * a.x),
    ];
    let mut y = [0.0; 64];
    eval_basis(MAX_BANDS, a, &mut y);
    let funk_hecke: Vec<f64> = (0..64).map(|i| clamped_cosine_a_hat(band_of(i)) * y[i]).collect();
    for i in 0..9 {
        assert!((by_hand[i] - funk_hecke[i]).abs() < 1e-12, "closed form {i}");
    }
    let err = |sh: &ShCoeffs| {
        (0..64)
            .map(|i| (0..3).map(|k| (sh.coeffs()[i][k] - funk_hecke[i]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max)
    };
    let quad = project_quadrature(&img, &raw(8)).unwrap();
    let mc = project_monte_carlo(&img, &raw(8), 256, 1).unwrap();
    let (eq, em) = (err(&quad), err(&mc));
    println!("clamped-cosine lobe, 1024x512, 8 bands: max coefficient error quadrature {eq:.2e}, MC 256^2 {em:.2e}");
    // Quadrature: the midpoint rule (1e-5 level) plus the f32 map.
    assert!(eq < 5e-5, "quadrature error {eq}");
    assert!(em < 5e-3, "Monte-Carlo error {em}");
}

/// A map lit only around one axis (by env.glsl's (u, v)) lights a plane
/// facing that axis and not one facing away; catches a mirrored or rotated
/// basis or map mapping.
#[test]
fn axis_convention() {
    let (w, h) = (256u32, 128u32);
    let near = |a: f64, b: f64, r: f64| (a - b).abs() < r;
    type InUv = Box<dyn Fn(f64, f64) -> bool>;
    let cases: [(&str, DVec3, InUv); 6] = [
        // atan2(1, 0) = pi/2 -> u = 0.75; v = acos(0)/pi = 0.5.
        ("+X", DVec3::X, Box::new(move |u, v| near(u, 0.75, 0.03) && near(v, 0.5, 0.06))),
        ("-X", DVec3::NEG_X, Box::new(move |u, v| near(u, 0.25, 0.03) && near(v, 0.5, 0.06))),
        ("+Y", DVec3::Y, Box::new(move |_, v| v < 0.06)),
        ("-Y", DVec3::NEG_Y, Box::new(move |_, v| v > 0.94)),
        // The centre column is -Z; +Z is the seam u = 0 / 1.
        ("-Z", DVec3::NEG_Z, Box::new(move |u, v| near(u, 0.5, 0.03) && near(v, 0.5, 0.06))),
        ("+Z", DVec3::Z, Box::new(move |u, v| !(0.03..=0.97).contains(&u) && near(v, 0.5, 0.06))),
    ];
    for (name, axis, inside) in &cases {
        let img = map_from_uv(w, h, inside);
        for window in [Window::None, Window::Hann] {
            let e =
                project_quadrature(&img, &Projection { window, ..Default::default() }).unwrap().irradiance();
            let lit = e.eval(*axis)[0];
            let away = e.eval(-*axis)[0];
            let side = [DVec3::X, DVec3::Y, DVec3::Z]
                .iter()
                .filter(|s| s.dot(*axis).abs() < 0.5)
                .map(|s| e.eval(*s)[0])
                .fold(0.0f64, f64::max);
            println!("light {name}, {window:?}: E(facing) {lit:.4}, E(away) {away:.4}, E(side) <= {side:.4}");
            assert!(lit > 0.0 && away < 0.1 * lit, "{name} {window:?}: facing {lit}, away {away}");
            assert!(side < 0.6 * lit, "{name} {window:?}: side {side} vs facing {lit}");
        }
        // The reconstructed radiance peaks on the lit side too.
        let l = project_quadrature(&img, &raw(8)).unwrap();
        let l_hann = l.windowed(Window::Hann);
        println!(
            "   radiance, 8 bands: facing {:.3} away {:.3}; Hann facing {:.3} away {:.3}",
            l.eval(*axis)[0],
            l.eval(-*axis)[0],
            l_hann.eval(*axis)[0],
            l_hann.eval(-*axis)[0]
        );
    }
}

/// Minimum of the red channel over `n` Fibonacci directions.
pub(super) fn min_radiance(sh: &ShCoeffs, n: usize) -> (f64, DVec3) {
    fibonacci_sphere(n)
        .into_iter()
        .map(|d| (sh.eval(d).into_iter().fold(f64::INFINITY, f64::min), d))
        .fold((f64::INFINITY, DVec3::ZERO), |a, b| if b.0 < a.0 { b } else { a })
}

/// A single 6.5e4 texel on a constant 0.1 sky: unwindowed L2 rings negative,
/// Hann-windowed L2 (the default) does not. The sun's power here is
/// 6.5e4 x 3.3e-5 sr = 2.1, so the L2 kernel minima (-1.8 / -0.30 P / 4pi,
/// see `window`) predict about 0.1 - 0.31 and 0.1 - 0.05.
#[test]
fn window_removes_negative_lobe_of_a_sun() {
    let (w, h) = (1024u32, 512u32);
    let sky = 0.1f32;
    let mut img = HdrImage { width: w, height: h, rgb: vec![sky; 3 * (w * h) as usize] };
    let (sx, sy) = (700u32, 170u32);
    let t = 3 * (sy * w + sx) as usize;
    img.rgb[t..t + 3].copy_from_slice(&[6.5e4; 3]);
    let unwindowed = project_quadrature(&img, &raw(3)).unwrap();
    let (min_raw, at) = min_radiance(&unwindowed, 10_000);
    let mut mins = vec![];
    for window in [Window::Hann, Window::Lanczos] {
        mins.push((window, min_radiance(&unwindowed.windowed(window), 10_000).0));
    }
    let default = project_quadrature(&img, &Projection::default()).unwrap();
    let (min_default, _) = min_radiance(&default, 10_000);
    let sun = texel_dir(sx, sy, w, h, 0.0);
    println!(
        "sun 6.5e4 on sky {sky}: L2 min radiance unwindowed {min_raw:.4} (at {:.0} deg from the sun), \
         {mins:?}, default {min_default:.4}",
        at.dot(sun).acos().to_degrees()
    );
    assert!(min_raw < 0.0, "unwindowed L2 should ring negative (min {min_raw})");
    assert!(min_default >= 0.0, "default (Hann) window leaves negative radiance {min_default}");
    assert_eq!(default, unwindowed.windowed(Window::Hann));
}
