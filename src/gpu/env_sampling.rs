//! Environment importance sampling for the path tracer (glsl/path/env_sampling.glsl): piecewise
//! constant in luminance x sin(theta) over the equirectangular texels, as a marginal row CDF and
//! per-row CDFs (PBRT 3rd ed., 13.6.7). Layout: SCENE_ENV_CDF. The shader's pdf uses the same f32
//! values it samples with, so any table is unbiased; a small floor keeps every texel reachable
//! (bilinear filtering spreads a bright texel's light into dark neighbours' cells).

use crate::gpu::shared::ENV_CDF_HEADER;
use crate::scene::HdrImage;

/// Widest table: larger maps are box-filtered down to it (2 MiB of floats
/// at 1024 x 512, whatever the map's size).
pub const MAX_TABLE_WIDTH: u32 = 1024;

/// Each cell's weight gets this share of the mean cell weight added.
const FLOOR: f64 = 1e-3;

/// The table of the scene's map (the header alone without one) on the GPU.
pub fn upload(ctx: &crate::vk::Context, scene: &crate::scene::Scene) -> anyhow::Result<crate::vk::Buffer> {
    let table = match &scene.environment.map {
        Some(map) => table(map),
        None => empty_table(),
    };
    let usage = ash::vk::BufferUsageFlags::STORAGE_BUFFER;
    crate::vk::Buffer::with_data(ctx, "environment sampling table", bytemuck::cast_slice(&table), usage)
}

/// The header alone: no map, the shader samples the sphere uniformly.
pub fn empty_table() -> Vec<f32> {
    vec![0.0; ENV_CDF_HEADER as usize]
}

/// The table's size for a map: the map box-filtered by a whole factor until
/// at most MAX_TABLE_WIDTH wide.
pub fn table_size(map: &HdrImage) -> (u32, u32) {
    let f = map.width.div_ceil(MAX_TABLE_WIDTH).max(1);
    (map.width.div_ceil(f), map.height.div_ceil(f))
}

/// The sampling table of `map` (non-finite and negative texels count as 0,
/// as the upload makes them).
pub fn table(map: &HdrImage) -> Vec<f32> {
    let (w, h) = table_size(map);
    let f = map.width.div_ceil(MAX_TABLE_WIDTH).max(1);
    let mut weight = vec![0f64; (w * h) as usize];
    for (i, c) in map.rgb.chunks_exact(3).enumerate() {
        let (x, y) = (i as u32 % map.width, i as u32 / map.width);
        let v = |c: f32| if c.is_finite() { c.max(0.0) as f64 } else { 0.0 };
        let lum = 0.2126 * v(c[0]) + 0.7152 * v(c[1]) + 0.0722 * v(c[2]);
        weight[((y / f) * w + x / f) as usize] += lum;
    }
    let mean = weight.iter().sum::<f64>() / weight.len() as f64;
    let floor = if mean > 0.0 && mean.is_finite() { mean * FLOOR } else { 1.0 };
    for (row, cells) in weight.chunks_exact_mut(w as usize).enumerate() {
        let sin = (std::f64::consts::PI * (row as f64 + 0.5) / h as f64).sin();
        for c in cells {
            *c = (c.min(f64::MAX / 1e12) + floor) * sin;
        }
    }
    let mut out = Vec::with_capacity(ENV_CDF_HEADER as usize + (h + 1) as usize + (h * (w + 1)) as usize);
    out.extend([w as f32, h as f32, 1.0, 0.0]);
    let row_sums: Vec<f64> = weight.chunks_exact(w as usize).map(|r| r.iter().sum()).collect();
    out.extend(cdf(&row_sums));
    for r in weight.chunks_exact(w as usize) {
        out.extend(cdf(r));
    }
    out
}

/// n + 1 values from 0 to exactly 1, non-decreasing.
fn cdf(weights: &[f64]) -> Vec<f32> {
    let total: f64 = weights.iter().sum();
    let mut acc = 0.0;
    let mut out = vec![0.0f32];
    for (i, w) in weights.iter().enumerate() {
        acc += w;
        let v = if i + 1 == weights.len() { 1.0 } else { (acc / total) as f32 };
        out.push(v.max(*out.last().unwrap_or(&0.0)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shader's sampling (env_sample) on the host: (column, row, pdf in
    /// uv space) of the cell that (u1, u2) selects.
    fn sample(t: &[f32], u1: f32, u2: f32) -> (usize, usize, f64) {
        let (w, h) = (t[0] as usize, t[1] as usize);
        let hd = ENV_CDF_HEADER as usize;
        let find = |base: usize, n: usize, u: f32| {
            let (mut lo, mut hi) = (0, n);
            while lo + 1 < hi {
                let mid = (lo + hi) / 2;
                if t[base + mid] <= u {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            lo
        };
        let row = find(hd, h, u1);
        let cond = hd + h + 1 + row * (w + 1);
        let col = find(cond, w, u2);
        let p = (t[hd + row + 1] - t[hd + row]) as f64
            * h as f64
            * (t[cond + col + 1] - t[cond + col]) as f64
            * w as f64;
        (col, row, p)
    }

    /// A 64-bit LCG (Knuth's MMIX constants): uniform in [0, 1).
    struct Lcg(u64);

    impl Lcg {
        fn f(&mut self) -> f32 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
    }

    fn map(width: u32, height: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> HdrImage {
        let rgb = (0..width * height).flat_map(|i| f(i % width, i / width)).collect();
        HdrImage { width, height, rgb }
    }

    #[test]
    fn a_sun_texel_gets_its_share_of_the_samples() {
        // A 64x32 sky of radiance 1 with one texel 10^4 times brighter.
        let m = map(64, 32, |x, y| if (x, y) == (40, 10) { [1e4; 3] } else { [1.0; 3] });
        let t = table(&m);
        let (n, mut hits) = (200_000, 0);
        let mut rng = Lcg(7);
        for _ in 0..n {
            let (c, r, p) = sample(&t, rng.f(), rng.f());
            assert!(p > 0.0);
            hits += ((c, r) == (40, 10)) as u32;
        }
        // Its weight over the total, rows weighted by sin(theta).
        let sin = |r: u32| (std::f64::consts::PI * (r as f64 + 0.5) / 32.0).sin();
        let floor = (1e4 + 64.0 * 32.0 - 1.0) / (64.0 * 32.0) * FLOOR;
        let all: f64 = (0..32).map(|r| sin(r) * 64.0 * (1.0 + floor)).sum::<f64>() + sin(10) * (1e4 - 1.0);
        let share = sin(10) * (1e4 + floor) / all;
        let seen = hits as f64 / n as f64;
        assert!((seen - share).abs() < 0.01, "sampled {seen}, expected {share}");
        assert!(share > 0.5, "{share}");
    }

    #[test]
    fn the_estimate_of_the_maps_power_is_exact_in_expectation() {
        // E[L / pdf] over the sphere = the solid-angle integral of L, here
        // against the quadrature of the same piecewise-constant map.
        let m = map(32, 16, |x, y| [(x as f32 * 0.37).sin().abs() * 5.0, y as f32, 0.5]);
        let t = table(&m);
        let lum = |x: u32, y: u32| {
            let c = &m.rgb[3 * (y * 32 + x) as usize..][..3];
            0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
        };
        let pi = std::f64::consts::PI;
        let exact: f64 = (0..16)
            .flat_map(|y| (0..32).map(move |x| (x, y)))
            .map(|(x, y)| {
                let (t0, t1) = (pi * y as f64 / 16.0, pi * (y + 1) as f64 / 16.0);
                lum(x, y) * (t0.cos() - t1.cos()) * 2.0 * pi / 32.0
            })
            .sum();
        let mut rng = Lcg(3);
        let n = 100_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let (c, r, p_uv) = sample(&t, rng.f(), rng.f());
            // A point uniform in the cell: the solid-angle pdf is p_uv / (2 pi^2 sin theta).
            let v = (r as f64 + rng.f() as f64) / 16.0;
            let pdf = p_uv / (2.0 * pi * pi * (pi * v).sin().max(1e-6));
            sum += lum(c as u32, r as u32) / pdf;
        }
        let estimate = sum / n as f64;
        assert!((estimate / exact - 1.0).abs() < 0.01, "estimate {estimate}, exact {exact}");
    }

    #[test]
    fn cdfs_end_at_one_and_never_fall() {
        let black = map(8, 4, |_, _| [0.0; 3]);
        let bad = map(8, 4, |x, _| if x == 3 { [f32::NAN, f32::INFINITY, -1.0] } else { [2.0; 3] });
        let big = map(3000, 1500, |x, y| [(x + y) as f32, 1.0, 0.0]);
        for m in [&black, &bad, &big] {
            let t = table(m);
            let (w, h) = table_size(m);
            assert_eq!((t[0], t[1]), (w as f32, h as f32));
            assert!(w <= MAX_TABLE_WIDTH);
            let hd = ENV_CDF_HEADER as usize;
            let rows = std::iter::once(&t[hd..hd + h as usize + 1])
                .chain(t[hd + h as usize + 1..].chunks_exact(w as usize + 1));
            for c in rows {
                assert_eq!((c[0], *c.last().unwrap()), (0.0, 1.0));
                assert!(c.windows(2).all(|p| p[1] >= p[0] && p[1].is_finite()));
                // Every cell is reachable (the floor).
                assert!(c.windows(2).all(|p| p[1] > p[0]), "{:?}", &c[..4]);
            }
        }
        assert_eq!(table_size(&big), (1000, 500));
    }
}
