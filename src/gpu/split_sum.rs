//! The split-sum environment BRDF (Karis 2013, second factor): for n·v and perceptual roughness, the
//! scale A and bias B of Schlick's f0 and f90 in the GGX lobe's directional albedo, so the lobe's
//! environment light is the prefiltered environment (gpu/env_prefilter.rs) times f0 A + f90 B. A + B,
//! the albedo at f0 = f90 = 1, also gives the multiple-scattering compensation
//! 1 + f0 (1 / (A + B) - 1) (Turquin 2019) that every GGX lobe gets (glsl/common/split_sum.glsl).
//! Tabulated on the host: DFG_LUT_SIZE² cells, uploaded as a filtered texture.

use std::f32::consts::PI;

use anyhow::Result;
use ash::vk;

use super::environment::f32_to_f16;
use super::shared::DFG_LUT_SIZE;
use crate::vk::{Context, Image};

/// The raster's alpha floor (glsl/common/brdf.glsl), so the table and the lobes it scales agree.
const ALPHA_FLOOR: f32 = 1e-3;

/// Van der Corput / Hammersley point `i` of `n` in the unit square.
pub fn hammersley(i: u32, n: u32) -> (f32, f32) {
    ((i as f32 + 0.5) / n as f32, i.reverse_bits() as f32 * (1.0 / 4_294_967_296.0))
}

/// GGX alpha of a perceptual roughness, floored as the shaders do.
pub fn alpha_of(roughness: f32) -> f32 {
    (roughness * roughness).max(ALPHA_FLOOR)
}

/// The cosine of a half vector drawn from D(h) (n·h) for GGX alpha `a`, at uniform `u`.
pub fn ggx_cos_theta(u: f32, a: f32) -> f32 {
    ((1.0 - u) / (1.0 + (a * a - 1.0) * u)).max(0.0).sqrt()
}

/// Height-correlated Smith visibility G2 / (4 n·l n·v), as brdf.glsl's v_smith_ggx_correlated.
pub fn smith_visibility(nv: f32, nl: f32, a2: f32) -> f32 {
    let gv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
    let gl = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl).max(1e-12)
}

/// (A, B) at `nv` and perceptual `roughness` from `samples` half vectors drawn from D(h) (n·h): the
/// estimator of f cos / pdf = F V 4 n·l v·h / n·h, split by Schlick's weight Fc = (1 - v·h)^5.
pub fn dfg(nv: f32, roughness: f32, samples: u32) -> [f32; 2] {
    let nv = nv.clamp(1e-4, 1.0);
    let a = alpha_of(roughness);
    let a2 = a * a;
    // v in the x-z plane, n = +z.
    let v = [(1.0 - nv * nv).sqrt(), 0.0, nv];
    let (mut sa, mut sb) = (0.0f64, 0.0f64);
    for i in 0..samples {
        let (u1, u2) = hammersley(i, samples);
        let ct = ggx_cos_theta(u1, a);
        let st = (1.0 - ct * ct).max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let h = [st * phi.cos(), st * phi.sin(), ct];
        let vh = v[0] * h[0] + v[2] * h[2];
        let nl = 2.0 * vh * h[2] - v[2];
        if nl <= 0.0 || vh <= 0.0 {
            continue;
        }
        let g = smith_visibility(nv, nl, a2) * 4.0 * nl * vh / ct.max(1e-12);
        let fc = (1.0 - vh).powi(5);
        sa += ((1.0 - fc) * g) as f64;
        sb += (fc * g) as f64;
    }
    [(sa / samples as f64) as f32, (sb / samples as f64) as f32]
}

/// The table: row y (perceptual roughness (y + 0.5) / size), column x (n·v (x + 0.5) / size), so
/// bilinear filtering at (n·v, roughness) meets the cells' centres.
pub fn dfg_lut() -> Vec<[f32; 2]> {
    let n = DFG_LUT_SIZE;
    let centre = |i: u32| (i as f32 + 0.5) / n as f32;
    (0..n * n).map(|k| dfg(centre(k % n), centre(k / n), 1024)).collect()
}

/// The table as an RG16F texture (half's 1e-3 steps are below the table's own sampling noise),
/// tabulated once per process: every renderer uploads the same.
pub fn upload(ctx: &Context) -> Result<Image> {
    static TEXELS: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    let texels = TEXELS
        .get_or_init(|| dfg_lut().iter().flatten().flat_map(|v| f32_to_f16(*v).to_le_bytes()).collect());
    let extent = vk::Extent2D { width: DFG_LUT_SIZE, height: DFG_LUT_SIZE };
    Image::texture(ctx, "split-sum DFG table", vk::Format::R16G16_SFLOAT, extent, texels, false)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ (D V n·l) F dω over the hemisphere by a midpoint grid in (θ, φ): an estimator independent of
    /// the importance sampling above (f0 = f90 = 1 gives A + B; `schlick` false gives A + B with F = 1
    /// too, so the split is checked through B = ∫ Fc ...).
    fn grid(nv: f32, roughness: f32, weight_fc: bool) -> f64 {
        let a = alpha_of(roughness);
        let a2 = a * a;
        let v = glam::Vec3::new((1.0 - nv * nv).sqrt(), 0.0, nv);
        let (nt, np) = (600, 600);
        let mut sum = 0.0f64;
        for i in 0..nt {
            let t = (i as f32 + 0.5) / nt as f32 * PI / 2.0;
            for j in 0..np {
                let p = (j as f32 + 0.5) / np as f32 * 2.0 * PI;
                let l = glam::Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                let h = (l + v).normalize();
                let d = h.z * h.z * (a2 - 1.0) + 1.0;
                let dggx = a2 / (PI * d * d);
                let f = dggx * smith_visibility(nv, l.z, a2) * l.z;
                let fc = if weight_fc { (1.0 - v.dot(h).max(0.0)).powi(5) } else { 1.0 };
                let dw = (PI / 2.0 / nt as f32) * (2.0 * PI / np as f32) * t.sin();
                sum += (f * fc * dw) as f64;
            }
        }
        sum
    }

    #[test]
    fn table_agrees_with_a_grid_integration_of_the_lobe() {
        for (nv, r) in [(1.0, 0.5), (0.5, 0.5), (0.2, 0.8), (0.9, 1.0), (0.3, 0.3)] {
            let [a, b] = dfg(nv, r, 4096);
            let total = grid(nv, r, false);
            let bias = grid(nv, r, true);
            assert!(
                ((a + b) as f64 - total).abs() < 0.01,
                "n.v {nv} roughness {r}: A+B {} vs {total}",
                a + b
            );
            assert!((b as f64 - bias).abs() < 0.005, "n.v {nv} roughness {r}: B {b} vs {bias}");
        }
    }

    #[test]
    fn smooth_lobes_reflect_everything_and_rough_ones_lose_energy_to_single_scattering() {
        // A smooth lobe's albedo at f0 = f90 = 1 is 1 (no shadowing, F = 1).
        let [a, b] = dfg(0.8, 0.05, 1024);
        assert!((a + b - 1.0).abs() < 0.01, "{}", a + b);
        // Closed form at alpha 1 and normal incidence: D = 1/pi, V = 1 / (2 (n.l + 1)), so the albedo
        // is the integral of mu / (1 + mu) over [0, 1], 1 - ln 2 (single scattering loses 69 %).
        let [a, b] = dfg(1.0, 1.0, 4096);
        assert!((a + b - (1.0 - 2f32.ln())).abs() < 2e-3, "{}", a + b);
        let lut = dfg_lut();
        assert_eq!(lut.len(), (DFG_LUT_SIZE * DFG_LUT_SIZE) as usize);
        for (k, [a, b]) in lut.iter().enumerate() {
            assert!(a.is_finite() && b.is_finite() && *a >= 0.0 && *b >= 0.0, "cell {k}: {a} {b}");
            assert!(a + b <= 1.01, "cell {k}: A + B = {}", a + b);
        }
        // Energy falls with roughness at every n·v.
        let n = DFG_LUT_SIZE as usize;
        for x in 0..n {
            let e = |y: usize| lut[y * n + x][0] + lut[y * n + x][1];
            assert!(e(n - 1) < e(0), "column {x}: {} vs {}", e(n - 1), e(0));
        }
    }
}
