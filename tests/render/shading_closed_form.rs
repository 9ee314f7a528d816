//! The compiled shading functions (glsl/common/{brdf,fresnel,offset}.glsl,
//! run through glsl/probes/shading.comp) against closed forms: Fresnel at
//! normal and grazing incidence and at the critical angle, Schlick against
//! the exact dielectric Fresnel within a stated error, GGX normalisation,
//! white-furnace tests of the BRDF, refraction by Snell's law, and the
//! self-intersection offset (ULPs of the triangle extent), and the
//! G-buffer's octahedral normal encoding (round-trip angle bound).
use crate::common;

use std::f64::consts::PI;

use common::probe::{run, Case};

/// Exact unpolarized dielectric Fresnel in f64; eta = n_i / n_t.
fn fresnel_exact(cos_i: f64, eta: f64) -> f64 {
    if eta == 1.0 {
        return 0.0; // no interface (the formula is 0/0 at grazing)
    }
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

#[test]
fn fresnel_matches_the_exact_dielectric_formula() {
    let etas: [f64; 7] = [1.0 / 1.5, 1.5, 1.0 / 2.42, 2.42, 1.0 / 1.0001, 1.0001, 1.0];
    let cosines: Vec<f64> = (0..=200).map(|i| i as f64 / 200.0).chain([1e-4, 1e-6, 0.9999]).collect();
    let cases: Vec<Case> =
        etas.iter().flat_map(|&e| cosines.iter().map(move |&c| Case::fresnel(c as f32, e as f32))).collect();
    let got = run(&cases);
    let mut i = 0;
    for &eta in &etas {
        for &c in &cosines {
            let g = got[i][0] as f64;
            i += 1;
            // Away from the critical angle, where F jumps, f32 agrees closely.
            let crit = if eta > 1.0 { (1.0 - 1.0 / (eta * eta)).sqrt() } else { -1.0 };
            if (c - crit).abs() < 1e-3 {
                continue;
            }
            let e = fresnel_exact(c, eta);
            assert!((g - e).abs() < 2e-4, "F(cos {c}, eta {eta}) = {g}, exact {e}");
        }
    }
    // Normal incidence: ((n - 1) / (n + 1))², from either side.
    let n = run(&[Case::fresnel(1.0, 1.0 / 1.5), Case::fresnel(1.0, 1.5), Case::fresnel(1e-7, 1.0 / 1.5)]);
    assert!((n[0][0] - 0.04).abs() < 1e-6 && (n[1][0] - 0.04).abs() < 1e-6, "{n:?}");
    // Grazing incidence reflects everything.
    assert!(n[2][0] > 0.999, "grazing: {}", n[2][0]);
}

#[test]
fn no_total_internal_reflection_at_ior_one_and_below_the_critical_angle() {
    // eta = 1: no interface at any angle, grazing included (f32 rounding of
    // 1 - sin² used to report TIR at cos 1e-4).
    let cos = [1.0f32, 0.5, 1e-2, 1e-4, 1e-6];
    let one = run(&cos.map(|c| Case::fresnel(c, 1.0)));
    for (c, r) in cos.iter().zip(&one) {
        assert!(r[0] < 1e-6, "IOR 1 reflects {} at cos {c}", r[0]);
    }
    // Inside glass (eta 1.5) TIR starts at the critical angle, asin(1/1.5).
    let crit = (1.0f64 - 1.0 / 2.25).sqrt() as f32;
    let r = run(&[Case::fresnel(crit * 1.01, 1.5), Case::fresnel(crit * 0.99, 1.5)]);
    assert!(r[0][0] < 1.0 && r[1][0] == 1.0, "around the critical angle: {r:?}");
}

#[test]
fn refraction_obeys_snell_and_is_the_identity_at_ior_one() {
    let mut cases = Vec::new();
    let angles = [0.0f64, 10.0, 30.0, 60.0, 89.0, 89.99];
    for &eta in &[1.0f64, 1.0 / 1.5, 1.5] {
        for &deg in &angles {
            let t = deg.to_radians();
            cases.push(Case::refract([t.sin() as f32, 0.0, -t.cos() as f32], [0.0, 0.0, 1.0], eta as f32));
        }
    }
    let got = run(&cases);
    let mut k = 0;
    for &eta in &[1.0f64, 1.0 / 1.5, 1.5] {
        for &deg in &angles {
            let d = got[k];
            k += 1;
            let sin_t = eta * deg.to_radians().sin();
            if sin_t >= 1.0 {
                assert_eq!(d[..3], [0.0, 0.0, 0.0], "TIR gives no direction (eta {eta}, {deg}°)");
                continue;
            }
            let len = (d[0] as f64).hypot(d[2] as f64);
            assert!((len - 1.0).abs() < 1e-5, "refracted direction not unit: {d:?}");
            assert!((d[0] as f64 - sin_t).abs() < 1e-5 && d[2] < 0.0, "eta {eta}, {deg}°: {d:?}");
            if eta == 1.0 {
                let i = [cases[k - 1].p[0], cases[k - 1].p[2]];
                assert_eq!([d[0], d[2]], i, "IOR 1 bends a ray at {deg}°");
            }
        }
    }
}

#[test]
fn schlick_stays_within_its_stated_error_of_the_exact_fresnel() {
    // Max |Schlick - exact| over all angles (f64 analysis of the formula,
    // which the GLSL must reproduce): 0.060 at IOR 1.33, 0.036 at 1.5,
    // 0.076 at 2.42; exactly 0 at IOR 1 (f0 = 0 and so f90 = 0).
    for (ior, bound) in [(1.33f64, 0.061), (1.5, 0.037), (2.42, 0.077), (1.0, 1e-7)] {
        let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        let cos: Vec<f64> = (0..=400).map(|i| i as f64 / 400.0).collect();
        let got = run(&cos.iter().map(|&c| Case::schlick(f0 as f32, c as f32)).collect::<Vec<_>>());
        let mut worst = 0.0f64;
        for (c, g) in cos.iter().zip(&got) {
            let f90 = (f0 * 50.0).min(1.0);
            let schlick = f0 + (f90 - f0) * (1.0 - c).powi(5);
            assert!((g[0] as f64 - schlick).abs() < 1e-5, "GLSL Schlick {} vs {schlick} at cos {c}", g[0]);
            worst = worst.max((g[0] as f64 - fresnel_exact(*c, 1.0 / ior)).abs());
        }
        eprintln!("Schlick vs exact Fresnel, IOR {ior}: max error {worst:.4}");
        assert!(worst <= bound, "IOR {ior}: Schlick off by {worst} > {bound}");
    }
}

#[test]
fn ggx_distribution_is_normalised_and_smith_matches_its_closed_form() {
    // ∫ D(h) (n.h) dω_h = 1 for every roughness: 2π ∫ D(cos θ) cos θ sin θ dθ.
    let n = 8192;
    for a2 in [1e-2f64, 0.0625, 0.25, 1.0] {
        let cases: Vec<Case> = (0..n)
            .map(|i| {
                let t = (i as f64 + 0.5) / n as f64 * PI / 2.0;
                Case::ggx(t.cos() as f32, a2 as f32, 1.0, 1.0)
            })
            .collect();
        let got = run(&cases);
        let integral: f64 = got
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let t = (i as f64 + 0.5) / n as f64 * PI / 2.0;
                d[0] as f64 * t.cos() * t.sin() * 2.0 * PI * (PI / 2.0 / n as f64)
            })
            .sum();
        assert!((integral - 1.0).abs() < 2e-3, "GGX D at alpha² {a2} integrates to {integral}");
    }
    // Height-correlated Smith (Heitz 2014): V = 0.5 / (n_l Λv' + n_v Λl').
    for (nv, nl, a2) in [(1.0f64, 1.0, 0.25), (0.3, 0.8, 0.0625), (0.05, 0.9, 1.0), (0.7, 0.2, 0.01)] {
        let g = run(&[Case::ggx(1.0, a2 as f32, nv as f32, nl as f32)])[0][1] as f64;
        let v = 0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
        assert!((g - v).abs() < 1e-5 * v.max(1.0), "V({nv}, {nl}, {a2}) = {g}, closed form {v}");
    }
}

/// Directional albedo ∫ f(v, l) (n.l) dω_l of the compiled BRDF for a view
/// at `view_deg` from the normal (midpoint rule over the hemisphere; the
/// BRDF is symmetric in φ about the view plane).
fn albedo(base: f32, metallic: f32, roughness: f32, ior: f32, view_deg: f64) -> f64 {
    let (nt, np) = (256, 128);
    let vt = view_deg.to_radians();
    let v = [vt.sin() as f32, 0.0, vt.cos() as f32];
    let mut cases = Vec::with_capacity(nt * np);
    for i in 0..nt {
        let t = (i as f64 + 0.5) / nt as f64 * PI / 2.0;
        for j in 0..np {
            let p = (j as f64 + 0.5) / np as f64 * PI;
            let l = [(t.sin() * p.cos()) as f32, (t.sin() * p.sin()) as f32, t.cos() as f32];
            cases.push(Case::brdf(base, metallic, roughness, 0.0, ior, v, l));
        }
    }
    let got = run(&cases);
    let dw = (PI / 2.0 / nt as f64) * (PI / np as f64) * 2.0;
    (0..nt)
        .flat_map(|i| (0..np).map(move |j| (i, j)))
        .map(|(i, j)| {
            let t = (i as f64 + 0.5) / nt as f64 * PI / 2.0;
            got[i * np + j][0] as f64 * t.sin() * dw
        })
        .sum()
}

#[test]
fn white_furnace() {
    // A white Lambertian surface (IOR 1: no specular layer) reflects all
    // the light it gets, at every view angle.
    for view in [0.0, 45.0, 80.0] {
        let a = albedo(1.0, 0.0, 0.8, 1.0, view);
        assert!((a - 1.0).abs() < 3e-3, "white diffuse albedo {a} at view {view}°");
    }
    // A white metal (F = 1) never reflects more than it gets; GGX with
    // single scattering loses energy as roughness grows, so the albedo
    // falls monotonically with roughness at normal view.
    let mut last = 1.01;
    for r in [0.5f32, 0.75, 1.0] {
        let a = albedo(1.0, 1.0, r, 1.5, 0.0);
        eprintln!("white metal, roughness {r}: albedo {a:.4}");
        assert!(a <= 1.0 + 2e-3 && a < last && a > 0.2, "metal albedo {a} at roughness {r}");
        last = a;
    }
    // A white dielectric plastic (IOR 1.5): glTF's layering (a Lambertian
    // base weighted by 1 - F(v.h) per light direction under a GGX coat) is
    // not exactly energy conserving: measured 0.997 at normal view, 1.011 at
    // 60°, within 2% up to there; it gains more at grazing views (1.115 at
    // 85°), a property of the model, printed here and not asserted.
    let grazing = albedo(1.0, 0.0, 0.5, 1.5, 85.0);
    eprintln!("white plastic, view 85°: albedo {grazing:.4} (glTF layering gains energy at grazing views)");
    assert!(grazing.is_finite() && grazing < 1.2);
    for view in [0.0, 30.0, 60.0] {
        let a = albedo(1.0, 0.0, 0.5, 1.5, view);
        eprintln!("white plastic, view {view}°: albedo {a:.4}");
        assert!(a <= 1.02 && a > 0.8, "white plastic albedo {a} at view {view}°");
    }
}

/// The offset origin must be strictly on the normal's side of the surface
/// point, by 16 ULPs of the larger of the point's and its triangle's
/// coordinates (never 0, never more): near the origin, far from it, and at
/// a small point on a large triangle, where the triangle's magnitude rules.
#[test]
fn ray_offset_leaves_the_surface_by_ulps_of_the_triangle_extent() {
    let normals = [[0.0f32, 0.0, 1.0], [0.577_350_3, -0.577_350_3, 0.577_350_3], [-0.267, 0.802, -0.534]];
    let points =
        [[0.0f32, 0.0, 0.0], [1e-3, -2e-3, 1e-4], [1.0, -2.0, 3.0], [1e5, -3e4, 1e5], [-1e6, 1e6, 2e6]];
    let extents = [0.0f32, 1e-6, 2e4];
    let mut cases = Vec::new();
    for p in points {
        for n in normals {
            for e in extents {
                cases.push(Case::offset(p, n, e));
            }
        }
    }
    let got = run(&cases);
    let mut k = 0;
    for p in points {
        for n in normals {
            for e in extents {
                let o = got[k];
                k += 1;
                let d: f64 = (0..3).map(|i| (o[i] as f64 - p[i] as f64) * n[i] as f64).sum();
                let m = p.iter().fold(e, |m, v| m.max(v.abs())).max(1e-30);
                let ulp = (f32::from_bits(m.to_bits() + 1) - m) as f64;
                let what = format!("offset of {p:?} (extent {e}) along {n:?}: moved {d}, ULP {ulp}");
                assert!(d >= 15.0 * ulp, "{what}: less than 15 ULPs");
                assert!(d <= 17.0 * ulp, "{what}: more than 17 ULPs");
            }
        }
    }
}

/// Largest angle (degrees) between a unit normal and its G-buffer round
/// trip (glsl/common/gbuffer_pack.glsl: octahedral, two 16-bit snorms). The
/// quantization step is 1/32767 in the octahedron's square; measured max
/// 0.0036 degrees over the directions below.
const OCTAHEDRAL_MAX_DEG: f64 = 0.005;

/// The round trip over a Fibonacci sphere, the axes, the octahedron's
/// fold (z = 0, both signs) and near-poles stays within OCTAHEDRAL_MAX_DEG,
/// decodes to unit length, and the axes come back exactly.
#[test]
fn octahedral_normals_round_trip_within_the_stated_angle() {
    let mut dirs: Vec<[f64; 3]> = Vec::new();
    let n = 20_000;
    let golden = PI * (3.0 - 5f64.sqrt());
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f64;
        dirs.push([r * phi.cos(), r * phi.sin(), z]);
    }
    for k in 0..360 {
        let a = (k as f64).to_radians();
        for z in [0.0, -1e-7, 1e-7, -0.999_999, 0.999_999] {
            let r = (1.0f64 - z * z).sqrt();
            dirs.push([r * a.cos(), r * a.sin(), z]);
        }
    }
    let axes: [[f64; 3]; 6] = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    dirs.extend(axes);
    let cases: Vec<Case> = dirs.iter().map(|d| Case::octahedral(d.map(|v| v as f32))).collect();
    let got = run(&cases);
    let mut worst = (0.0f64, [0.0; 3]);
    for (d, o) in dirs.iter().zip(&got) {
        let o = [o[0] as f64, o[1] as f64, o[2] as f64];
        let len = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt();
        assert!((len - 1.0).abs() < 1e-6, "decoded {o:?} of {d:?} is not unit length ({len})");
        let cos = (d[0] * o[0] + d[1] * o[1] + d[2] * o[2]) / len;
        let deg = cos.clamp(-1.0, 1.0).acos().to_degrees();
        if deg > worst.0 {
            worst = (deg, *d);
        }
    }
    assert!(
        worst.0 <= OCTAHEDRAL_MAX_DEG,
        "octahedral round trip of {:?} is {} degrees off (bound {OCTAHEDRAL_MAX_DEG})",
        worst.1,
        worst.0
    );
    for (k, a) in axes.iter().enumerate() {
        let o = got[got.len() - 6 + k];
        assert_eq!([o[0] as f64, o[1] as f64, o[2] as f64], *a, "axis {a:?} does not come back exactly");
    }
    eprintln!("octahedral round trip: max {:.5} degrees", worst.0);
}
