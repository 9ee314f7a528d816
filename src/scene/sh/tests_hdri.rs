//! Tests on the shipped Poly Haven maps (1024x512): irradiance accuracy
//! against brute force, the two integrators side by side, rotation against
//! re-projection, windowing under venice_sunset, and projection timings.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::DVec3;

use super::tests_maps::{min_radiance, raw};
use super::*;
use crate::scene::HdrImage;

const MAPS: [&str; 5] = [
    "empty_warehouse_01_1k",
    "potsdamer_platz_1k",
    "st_fagans_interior_1k",
    "studio_small_03_1k",
    "venice_sunset_1k",
];

fn map_path(name: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/assets/hdri/polyhaven_1k"))
        .join(format!("{name}.hdr"))
}

fn load(name: &str) -> HdrImage {
    let path = map_path(name);
    assert!(path.is_file(), "missing test asset {}", path.display());
    let img = crate::scene::scene_file::load_hdr(&path).unwrap();
    assert_eq!((img.width, img.height), (1024, 512), "{name}");
    img
}

/// Box-filters the map by `f` x `f` texels (in (u, v), like a mip level).
fn downsample(img: &HdrImage, f: u32) -> HdrImage {
    let (w, h) = (img.width / f, img.height / f);
    let mut rgb = vec![0.0f32; 3 * (w * h) as usize];
    for y in 0..img.height.min(h * f) {
        for x in 0..img.width.min(w * f) {
            let (s, d) = (3 * (y * img.width + x) as usize, 3 * ((y / f) * w + x / f) as usize);
            for k in 0..3 {
                rgb[d + k] += img.rgb[s + k] / (f * f) as f32;
            }
        }
    }
    HdrImage { width: w, height: h, rgb }
}

/// E(n) = sum over texels of L max(0, n·w) dw (the same texel-centre
/// directions and exact solid angles as the quadrature projection).
fn brute_force_irradiance(img: &HdrImage, normals: &[DVec3]) -> Vec<[f64; 3]> {
    let (w, h) = (img.width, img.height);
    let mut out = vec![[0.0; 3]; normals.len()];
    for y in 0..h {
        let omega = texel_solid_angle(y, w, h);
        for x in 0..w {
            let d = texel_dir(x, y, w, h, 0.0);
            let t = 3 * (y * w + x) as usize;
            for (e, n) in out.iter_mut().zip(normals) {
                let c = n.dot(d).max(0.0) * omega;
                for (ek, &lk) in e.iter_mut().zip(&img.rgb[t..t + 3]) {
                    *ek += lk as f64 * c;
                }
            }
        }
    }
    out
}

/// Irradiance errors over a set of normals, per normal and RGB channel.
struct IrradianceError {
    /// mean and max of |E_sh - E| / E: the "mean relative error".
    rel_mean: f64,
    rel_max: f64,
    /// sum |E_sh - E| / sum E: relative to the mean irradiance.
    nmae: f64,
    /// mean |E_sh - E| / max E: Ramamoorthi & Hanrahan's normalisation (for
    /// a single directional light L2 gives 3.1% on average and 9.4% at
    /// worst in this measure, their "3%" and "9%").
    peak: f64,
}

fn irradiance_error(sh: &ShCoeffs, normals: &[DVec3], reference: &[[f64; 3]]) -> IrradianceError {
    let (mut rel, mut rel_max, mut abs, mut tot, mut emax) = (0.0, 0.0f64, 0.0, 0.0, 0.0f64);
    for (n, r) in normals.iter().zip(reference) {
        let got = sh.eval(*n);
        for k in 0..3 {
            let d = (got[k] - r[k]).abs();
            rel += d / r[k];
            rel_max = rel_max.max(d / r[k]);
            abs += d;
            tot += r[k];
            emax = emax.max(r[k]);
        }
    }
    let count = (3 * normals.len()) as f64;
    IrradianceError { rel_mean: rel / count, rel_max, nmae: abs / tot, peak: abs / count / emax }
}

/// Maps whose small, strong lights leave directions with almost no
/// irradiance (brute-force E spans 0.25..23), where the per-normal relative
/// error of L2 is far above 3% (30% mean; L2 even goes negative there).
const DARK_DIRECTIONS: [&str; 1] = ["studio_small_03_1k"];

/// Irradiance of L2 (bands 3) against brute force on 64 Fibonacci normals,
/// on each shipped map box-filtered to 128x64 (both sides see the same
/// data, texel-centre directions and exact solid angles, so the difference
/// is the SH truncation and window alone).
///
/// The 3% is taken as plain truncation (`Window::None`), which is
/// what Ramamoorthi & Hanrahan's figures refer to: mean per-normal relative
/// error < 3% on every map but `DARK_DIRECTIONS`, and mean |dE| / max E
/// (R&H's normalisation) < 3% on all five. The windowed (default Hann)
/// errors are printed and not bounded: Hann at width 3 scales band 1 by
/// 0.75 and band 2 by 0.25, costing 9-25% (114% on studio_small_03); what
/// is asserted for them is that the windowed irradiance stays non-negative.
#[test]
fn l2_irradiance_vs_brute_force_on_shipped_maps() {
    let normals = fibonacci_sphere(64);
    for name in MAPS {
        let img = downsample(&load(name), 8);
        let reference = brute_force_irradiance(&img, &normals);
        let emin = reference.iter().flatten().copied().fold(f64::INFINITY, f64::min);
        let emax = reference.iter().flatten().copied().fold(0.0, f64::max);
        println!("{name} (128x64, brute-force E in [{emin:.3}, {emax:.3}]), L2 irradiance error:");
        for window in [Window::None, Window::Hann, Window::Lanczos] {
            let e = project_quadrature(&img, &Projection { bands: 3, window, ..Default::default() })
                .unwrap()
                .irradiance();
            let err = irradiance_error(&e, &normals, &reference);
            let (emin_sh, _) = min_radiance(&e, 10_000);
            println!(
                "    {:8} per-normal relative: mean {:6.2}% max {:7.2}% | sum|dE|/sum E {:5.2}% | \
                 mean|dE|/max E {:5.2}% | min E over 10k dirs {emin_sh:.3}",
                format!("{window:?}"),
                100.0 * err.rel_mean,
                100.0 * err.rel_max,
                100.0 * err.nmae,
                100.0 * err.peak,
            );
            if window == Window::None {
                assert!(err.peak < 0.03, "{name}: L2 irradiance error {} of the peak irradiance", err.peak);
                if !DARK_DIRECTIONS.contains(&name) {
                    assert!(
                        err.rel_mean < 0.03,
                        "{name}: L2 irradiance mean relative error {}",
                        err.rel_mean
                    );
                }
            } else {
                assert!(
                    emin_sh >= 0.0,
                    "{name} {window:?}: windowed L2 irradiance goes negative ({emin_sh})"
                );
            }
        }
    }
}

/// Exact quadrature vs Monte-Carlo with N = 16, 64, 256 (and 1024, printed)
/// on the full-size map, bands 3 and 8, no window: the RMS coefficient
/// difference relative to |L00| must fall with N on st_fagans_interior
/// and be below 2e-3 at N = 1024 (measured 6.3e-4).
/// venice_sunset is printed only: its sun is 2-3 texels (6496, 3296) that
/// carry ~2% of L00, which fewer samples than texels (N <= 256: 65k vs
/// 524k) hit or miss by chance, so its error plateaus at ~2% until N ~ 1024
/// (it converges: 2.4e-4 at N = 2048 with seed 1; no bias).
#[test]
fn integrators_side_by_side() {
    for (name, asserted) in [("st_fagans_interior_1k", true), ("venice_sunset_1k", false)] {
        let img = load(name);
        for bands in [3, 8] {
            let exact = project_quadrature(&img, &raw(bands)).unwrap();
            let scale = exact.coeffs()[0].iter().map(|v| v * v).sum::<f64>().sqrt();
            let mut prev = f64::INFINITY;
            let mut line =
                format!("{name:22} bands {bands}: MC vs quadrature, RMS coefficient difference / |L00|:");
            for n in [16u32, 64, 256, 1024] {
                let mc = project_monte_carlo(&img, &raw(bands), n, 5).unwrap();
                let sq: f64 = mc
                    .coeffs()
                    .iter()
                    .zip(exact.coeffs())
                    .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).powi(2)))
                    .sum();
                let rms = (sq / (3 * bands * bands) as f64).sqrt() / scale;
                line += &format!("  N={n}: {rms:.2e}");
                if asserted && n <= 256 {
                    assert!(
                        rms < prev,
                        "{name} bands {bands}: MC error did not fall at N = {n} ({rms} >= {prev})"
                    );
                }
                // And it converges to the quadrature, not just somewhere.
                if asserted && n == 1024 {
                    assert!(rms < 2e-3, "{name} bands {bands}: MC N = 1024 still {rms} off");
                }
                prev = rms;
            }
            println!("{line}");
        }
    }
}

/// Rotating coefficients equals projecting the rotated map. For the
/// quadrature this is exact up to rounding (the rotated projection sums the
/// same texels against y_lm(theta, phi - r), itself a combination of
/// y_l,+-m); the MC projection reads other texels, so its tolerance is its
/// own noise level.
#[test]
fn rotation_matches_reprojection() {
    let img = downsample(&load("potsdamer_platz_1k"), 4);
    let base = Projection { bands: 8, rotation: 0.4, intensity: 1.5, window: Window::None };
    let c0 = project_quadrature(&img, &base).unwrap();
    let c0_mc = project_monte_carlo(&img, &base, 256, 3).unwrap();
    let largest = max_abs(&c0);
    for angle in [0.9, -2.2, std::f64::consts::PI] {
        let rotated = Projection { rotation: base.rotation + angle, ..base };
        let direct = project_quadrature(&img, &rotated).unwrap();
        let diff = max_diff(&c0.rotated_y(angle), &direct) / largest;
        let mc_direct = project_monte_carlo(&img, &rotated, 256, 3).unwrap();
        let mc_diff = max_diff(&c0_mc.rotated_y(angle), &mc_direct) / largest;
        println!("rotation {angle:+.2}: max |rotated - reprojected| / max |c|: quadrature {diff:.1e}, MC 256^2 {mc_diff:.1e}");
        assert!(diff < 1e-10, "quadrature: {diff}");
        assert!(mc_diff < 2e-2, "MC: {mc_diff}");
        // The wrong sign is far off (r and -r differ unless r = pi).
        if angle != std::f64::consts::PI {
            assert!(max_diff(&c0.rotated_y(-angle), &direct) / largest > 1e-2);
        }
        // Windowing commutes with the rotation.
        let w = Projection { window: Window::Hann, ..rotated };
        let hann = project_quadrature(&img, &w).unwrap();
        assert!(max_diff(&c0.windowed(Window::Hann).rotated_y(angle), &hann) / largest < 1e-10);
    }
    // Intensity is a plain factor.
    let unit = project_quadrature(&img, &Projection { intensity: 1.0, ..base }).unwrap();
    assert!((c0.coeffs()[0][0] - 1.5 * unit.coeffs()[0][0]).abs() < 1e-9 * c0.coeffs()[0][0]);
}

fn max_abs(c: &ShCoeffs) -> f64 {
    c.coeffs().iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))
}

fn max_diff(a: &ShCoeffs, b: &ShCoeffs) -> f64 {
    a.coeffs()
        .iter()
        .flatten()
        .zip(b.coeffs().iter().flatten())
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// venice_sunset through the sun check: the L2 reconstruction's minimum
/// radiance over 10k directions, unwindowed and with each window.
#[test]
fn venice_sunset_window_minimum() {
    let img = load("venice_sunset_1k");
    let peak = img.rgb.iter().copied().fold(0.0f32, f32::max);
    let sh = project_quadrature(&img, &raw(3)).unwrap();
    let mins: Vec<(Window, f64)> = [Window::None, Window::Hann, Window::Lanczos]
        .into_iter()
        .map(|w| (w, min_radiance(&sh.windowed(w), 10_000).0))
        .collect();
    println!("venice_sunset (peak texel {peak:.0}): L2 min radiance {mins:?}");
    assert!(mins[1].1 >= 0.0, "Hann-windowed L2 of venice_sunset goes negative: {}", mins[1].1);
}

/// Projection time of each shipped 1024x512 map for both integrators (CPU,
/// one thread, this build's profile; the dev profile builds this crate at
/// opt-level 1); bench/results/ibl.md records them.
#[test]
fn projection_timings() {
    for name in MAPS {
        let img = load(name);
        for bands in [3, 8] {
            let p = raw(bands);
            let t = Instant::now();
            let q = project_quadrature(&img, &p).unwrap();
            let tq = t.elapsed();
            // 724^2 = 524k samples, as many as the map has texels.
            let t = Instant::now();
            let m = project_monte_carlo(&img, &p, 724, 1).unwrap();
            let tm = t.elapsed();
            assert!(q.coeffs()[0][0] > 0.0 && m.coeffs()[0][0] > 0.0);
            println!(
                "{name} 1024x512, {bands} bands: quadrature {:.0} ms, Monte-Carlo 724^2 {:.0} ms",
                tq.as_secs_f64() * 1e3,
                tm.as_secs_f64() * 1e3
            );
        }
    }
}
