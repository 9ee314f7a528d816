//! The environment prefiltered by GGX for every roughness (Karis 2013's split sum, first factor): level
//! k of an equirectangular mip chain holds the map convolved with the lobe of perceptual roughness
//! k / (ENV_SPECULAR_LEVELS - 1) about each direction (n = v = r), weighted by n·l. Samples are read
//! from a box-filtered mip chain of the map at the level their solid angle covers (filtered importance
//! sampling, Colbert & Křivánek 2007), so a small bright sun blurs instead of speckling. Level 0 is
//! the map resampled. Computed on the host at load, like the SH projection (gpu/env_sh.rs).

use std::f32::consts::PI;

use anyhow::Result;
use glam::Vec3;

use super::shared::ENV_SPECULAR_LEVELS;
use super::split_sum::{alpha_of, ggx_cos_theta, hammersley};
use crate::scene::HdrImage;

/// Level 0's size: 1.4° texels, sharp enough for the lobes below the mirror threshold (the map's own
/// resolution serves mirrors: env.glsl `environment`); the roughest level is then 16x8, the coarsest
/// grid that interpolates a lobe 90° wide within 2 % (8x4 missed by 8 %).
const BASE_WIDTH: u32 = 256;
/// Lobe samples per texel at level 1 (samples_at doubles them per level); filtered importance sampling
/// and the hot texels' exact sum keep this small (see the tests).
pub const SAMPLES: u32 = 64;

/// Perceptual roughness of level `k`.
pub fn level_roughness(k: u32) -> f32 {
    k as f32 / (ENV_SPECULAR_LEVELS - 1) as f32
}

/// Unit direction of equirectangular (u, v), as env.glsl's env_uv inverts it (+Y up, u = 0.5 looks
/// down -Z), before the map's rotation.
pub fn direction(u: f32, v: f32) -> Vec3 {
    let (phi, theta) = ((u - 0.5) * 2.0 * PI, v * PI);
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

pub fn uv_of(d: Vec3) -> (f32, f32) {
    (d.x.atan2(-d.z) / (2.0 * PI) + 0.5, d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// Half the size, each texel the mean of up to four (odd sizes drop their last row / column, as a
/// blit does).
fn downsample(img: &HdrImage) -> HdrImage {
    let (w, h) = ((img.width / 2).max(1), (img.height / 2).max(1));
    let mut rgb = vec![0.0; (w * h * 3) as usize];
    for y in 0..h {
        for x in 0..w {
            let mut c = Vec3::ZERO;
            let mut n = 0.0;
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (sx, sy) = ((2 * x + dx).min(img.width - 1), (2 * y + dy).min(img.height - 1));
                c += texel(img, sx, sy);
                n += 1.0;
            }
            let o = ((y * w + x) * 3) as usize;
            rgb[o..o + 3].copy_from_slice(&(c / n).to_array());
        }
    }
    HdrImage { width: w, height: h, rgb }
}

fn texel(img: &HdrImage, x: u32, y: u32) -> Vec3 {
    let o = ((y * img.width + x) * 3) as usize;
    Vec3::new(img.rgb[o], img.rgb[o + 1], img.rgb[o + 2])
}

/// Bilinear, u wrapping, v clamped: the shaders' environment sampler.
fn bilinear(img: &HdrImage, u: f32, v: f32) -> Vec3 {
    let x = u * img.width as f32 - 0.5;
    let y = (v * img.height as f32 - 0.5).clamp(0.0, (img.height - 1) as f32);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let w = img.width as i64;
    let xi = |x: f32| (x as i64).rem_euclid(w) as u32;
    let y1 = (y0 as u32 + 1).min(img.height - 1);
    let row = |y: u32| texel(img, xi(x0), y) * (1.0 - fx) + texel(img, xi(x0 + 1.0), y) * fx;
    row(y0 as u32) * (1.0 - fy) + row(y1) * fy
}

/// The map and its box mip chain.
struct Source {
    mips: Vec<HdrImage>,
}

impl Source {
    fn new(map: &HdrImage) -> Source {
        let mut mips = vec![map.clone()];
        while mips.last().is_some_and(|m| m.width > 1 || m.height > 1) {
            let next = downsample(mips.last().unwrap());
            mips.push(next);
        }
        Source { mips }
    }

    /// Trilinear lookup at (u, v) and mip `lod`.
    fn sample_uv(&self, u: f32, v: f32, lod: f32) -> Vec3 {
        let lod = lod.clamp(0.0, (self.mips.len() - 1) as f32);
        let (l0, t) = (lod.floor() as usize, lod.fract());
        let a = bilinear(&self.mips[l0], u, v);
        if t == 0.0 || l0 + 1 >= self.mips.len() {
            return a;
        }
        a * (1.0 - t) + bilinear(&self.mips[l0 + 1], u, v) * t
    }

    /// Solid angle of a level-0 texel in direction `d`.
    fn texel_solid_angle(&self, d: Vec3) -> f32 {
        let m = &self.mips[0];
        let sin_theta = (1.0 - d.y * d.y).max(0.0).sqrt().max(1e-4);
        (2.0 * PI / m.width as f32) * (PI / m.height as f32) * sin_theta
    }
}

/// One lobe sample for a row of texels: its offset in u from the texel's, its v, source mip and weight.
struct Tap {
    du: f32,
    v: f32,
    lod: f32,
    weight: f32,
}

/// The lobe about the texel at u = 0.5 of a row at `v` for alpha `a`, as `samples` taps (weights n·l
/// normalised). A turn about +Y only shifts u, and the taps' mips depend on elevation alone, so every
/// texel of the row reads the same taps shifted by its own u. Also returns the weights' mean over the
/// samples, the estimate of ∫ n·l pdf(l) dl that normalises the hot texels' explicit sum.
fn row_taps(src: &Source, v: f32, a: f32, samples: u32) -> (Vec<Tap>, f32) {
    let n = direction(0.5, v);
    let (t, b) = n.any_orthonormal_pair();
    let a2 = a * a;
    let mut taps = Vec::with_capacity(samples as usize);
    for i in 0..samples {
        let (u1, u2) = hammersley(i, samples);
        let ct = ggx_cos_theta(u1, a);
        let st = (1.0 - ct * ct).max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let h = t * (st * phi.cos()) + b * (st * phi.sin()) + n * ct;
        let l = (h * (2.0 * ct) - n).normalize();
        let nl = l.dot(n);
        if nl <= 0.0 {
            continue;
        }
        // pdf(l) = D(h) n·h / (4 v·h) = D / 4 with v = n; the +1 blurs a little more than the
        // sample's solid angle, as Colbert & Křivánek suggest.
        let d = ct * ct * (a2 - 1.0) + 1.0;
        let pdf = a2 / (PI * d * d) / 4.0;
        let lod = 0.5 * (1.0 / (samples as f32 * pdf * src.texel_solid_angle(l))).log2() + 1.0;
        let (lu, lv) = uv_of(l);
        taps.push(Tap { du: lu - 0.5, v: lv, lod, weight: nl });
    }
    let sum: f32 = taps.iter().map(|t| t.weight).sum();
    for t in &mut taps {
        t.weight /= sum.max(1e-12);
    }
    (taps, sum / samples as f32)
}

/// The lobe's weight n·l pdf(l) = n·l D(h) / 4 (v = n) for a unit `l`.
fn lobe_weight(n: Vec3, l: Vec3, a2: f32) -> f32 {
    let nl = n.dot(l);
    if nl <= 0.0 {
        return 0.0;
    }
    let ct = (n + l).normalize().dot(n);
    let d = ct * ct * (a2 - 1.0) + 1.0;
    nl * a2 / (PI * d * d) / 4.0
}

/// A texel of the hot mip whose light above HOT_OVER_MEAN x the mean luminance was taken out of the
/// sampled map: its direction, solid angle and that excess radiance.
struct HotTexel {
    dir: Vec3,
    solid_angle: f32,
    excess: Vec3,
}

/// The hot mip's width at most: 2.8° texels, sharper than the sharpest filtered level's lobe.
const HOT_WIDTH: u32 = 128;
/// Above this many times the mean luminance a texel is hot.
const HOT_OVER_MEAN: f32 = 16.0;
/// The hottest texels taken out at most (a sun covers a handful).
const MAX_HOT: usize = 1024;

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Splits a sun out of the map: lobe samples find a small bright source only with hundreds of them
/// (a 40000:1 sun 40° off a roughness-0.4 lobe came out 15 % low at 128), so the hottest texels'
/// light above the threshold is summed explicitly over each lobe instead; the rest is sampled.
/// Returns the map with those texels clamped, and the texels.
fn split_hot(map: &HdrImage) -> (HdrImage, Vec<HotTexel>) {
    let mut hot_mip = map.clone();
    let mut shift = 0;
    while hot_mip.width > HOT_WIDTH {
        hot_mip = downsample(&hot_mip);
        shift += 1;
    }
    let (hw, hh) = (hot_mip.width, hot_mip.height);
    let texels: Vec<Vec3> = (0..hw * hh).map(|i| texel(&hot_mip, i % hw, i / hw)).collect();
    let mean = luminance(super::environment::equirect_mean(texels.iter().copied(), hw, hh));
    let threshold = (HOT_OVER_MEAN * mean).max(1e-6);
    let mut ranked: Vec<u32> = (0..hw * hh).filter(|&i| luminance(texels[i as usize]) > threshold).collect();
    ranked.sort_by(|a, b| luminance(texels[*b as usize]).total_cmp(&luminance(texels[*a as usize])));
    ranked.truncate(MAX_HOT);
    let mut clamped = map.clone();
    let mut hot = Vec::with_capacity(ranked.len());
    for i in ranked {
        let (tx, ty) = (i % hw, i / hw);
        let (x0, y0) = (tx << shift, ty << shift);
        let (x1, y1) = (((tx + 1) << shift).min(map.width), ((ty + 1) << shift).min(map.height));
        let mut excess = Vec3::ZERO;
        for y in y0..y1 {
            for x in x0..x1 {
                let c = texel(map, x, y);
                let lum = luminance(c);
                if lum > threshold {
                    let keep = c * (threshold / lum);
                    excess += c - keep;
                    let o = ((y * map.width + x) * 3) as usize;
                    clamped.rgb[o..o + 3].copy_from_slice(&keep.to_array());
                }
            }
        }
        let count = ((x1 - x0) * (y1 - y0)).max(1) as f32;
        let (u, v) = ((x0 + x1) as f32 / 2.0 / map.width as f32, (y0 + y1) as f32 / 2.0 / map.height as f32);
        let dir = direction(u, v);
        let rows = (y1 - y0) as f32 / map.height as f32;
        let cols = (x1 - x0) as f32 / map.width as f32;
        let solid_angle = 2.0 * PI * cols * PI * rows * (1.0 - dir.y * dir.y).max(0.0).sqrt();
        hot.push(HotTexel { dir, solid_angle, excess: excess / count });
    }
    (clamped, hot)
}

/// Samples per texel at level `k` >= 1: doubling per level while texels quarter, so rough levels, whose
/// lobes span a hot sun's whole neighbourhood, are not noisier than sharp ones.
fn samples_at(k: u32, base: u32) -> u32 {
    base << (k.max(1) - 1)
}

/// Level extents: BASE_WIDTH x BASE_WIDTH / 2 halved per level, whatever the map's size.
pub fn level_extents() -> Vec<(u32, u32)> {
    (0..ENV_SPECULAR_LEVELS).map(|k| (BASE_WIDTH >> k, (BASE_WIDTH / 2) >> k)).collect()
}

/// The chain, and how many hot texels were summed explicitly.
pub struct Prefiltered {
    pub levels: Vec<HdrImage>,
    pub hot_texels: usize,
}

/// Every level of the chain, `samples` per texel at level 1 (doubling per level).
pub fn prefilter(map: &HdrImage, samples: u32) -> Result<Prefiltered> {
    let extents = level_extents();
    let mut out = Vec::with_capacity(extents.len());
    // Level 0 from the whole map; the lobes from the map without its hot texels, plus those.
    let (w0, h0) = extents[0];
    out.push(level(&Source::new(map), &[], w0, h0, 0.0, |v| {
        (vec![Tap { du: 0.0, v, lod: (map.width as f32 / w0 as f32).log2().max(0.0), weight: 1.0 }], 1.0)
    })?);
    let (clamped, hot) = split_hot(map);
    let src = Source::new(&clamped);
    for (k, &(w, h)) in extents.iter().enumerate().skip(1) {
        let a = alpha_of(level_roughness(k as u32));
        let n = samples_at(k as u32, samples);
        out.push(level(&src, &hot, w, h, a, |v| row_taps(&src, v, a, n))?);
    }
    Ok(Prefiltered { levels: out, hot_texels: hot.len() })
}

/// One level, `taps(v)` giving each row's taps and their normaliser.
fn level(
    src: &Source,
    hot: &[HotTexel],
    w: u32,
    h: u32,
    a: f32,
    taps: impl Fn(f32) -> (Vec<Tap>, f32) + Sync,
) -> Result<HdrImage> {
    let a2 = a * a;
    // One row per work item.
    let rows = crate::par::map(h as usize, &[], |y| {
        let v = (y as f32 + 0.5) / h as f32;
        let (taps, norm) = taps(v);
        let mut row = Vec::with_capacity(w as usize * 3);
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32;
            let mut c =
                taps.iter().fold(Vec3::ZERO, |c, t| c + src.sample_uv(u + t.du, t.v, t.lod) * t.weight);
            if !hot.is_empty() {
                let n = direction(u, v);
                let sum = hot
                    .iter()
                    .fold(Vec3::ZERO, |s, t| s + t.excess * (t.solid_angle * lobe_weight(n, t.dir, a2)));
                c += sum / norm.max(1e-12);
            }
            row.extend_from_slice(&c.to_array());
        }
        row
    })?;
    Ok(HdrImage { width: w, height: h, rgb: rows.concat() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(w: u32, h: u32, f: impl Fn(Vec3) -> Vec3) -> HdrImage {
        let mut rgb = Vec::new();
        for y in 0..h {
            for x in 0..w {
                rgb.extend(f(direction((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32)).to_array());
            }
        }
        HdrImage { width: w, height: h, rgb }
    }

    #[test]
    fn directions_and_texel_coordinates_invert_each_other() {
        for (u, v) in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7), (0.3, 0.95)] {
            let (u2, v2) = uv_of(direction(u, v));
            assert!((u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5, "({u}, {v}) -> ({u2}, {v2})");
        }
        // u = 0.5 looks down -Z; v = 0 is +Y.
        assert!((direction(0.5, 0.5) - Vec3::NEG_Z).length() < 1e-5);
        assert!((direction(0.3, 0.0) - Vec3::Y).length() < 1e-5);
    }

    #[test]
    fn a_constant_map_stays_constant_at_every_roughness() {
        let c = Vec3::new(0.5, 2.0, 7.0);
        let levels = prefilter(&map(64, 32, |_| c), SAMPLES).unwrap().levels;
        assert_eq!(levels.len(), ENV_SPECULAR_LEVELS as usize);
        for (k, l) in levels.iter().enumerate() {
            for (i, v) in l.rgb.iter().enumerate() {
                assert!((v / c[i % 3] - 1.0).abs() < 1e-4, "level {k} value {i}: {v}");
            }
        }
    }

    /// The lobe against a brute-force integral over the map's texels: a sky bright above the horizon
    /// (+Y) and a small hot sun, at a direction 30° above the horizon.
    #[test]
    fn levels_match_the_lobe_integrated_over_every_texel() {
        let sun = Vec3::new(0.6, 0.6, -0.53).normalize();
        let src = map(256, 128, |d| {
            let sky = if d.y > 0.0 { Vec3::new(0.3, 0.5, 1.0) } else { Vec3::splat(0.05) };
            sky + if d.dot(sun) > 0.995 { Vec3::splat(200.0) } else { Vec3::ZERO }
        });
        let levels = prefilter(&src, SAMPLES).unwrap().levels;
        let n = Vec3::new(0.0, 0.5, -(0.75f32).sqrt());
        for k in 1..ENV_SPECULAR_LEVELS {
            let a = alpha_of(level_roughness(k));
            let a2 = a * a;
            // Σ L(l) n·l D(h) / (4 n·h ... ) with v = n: the weight of l is D(h) / (4) times n·l times
            // the texel's solid angle (pdf of l is D / 4).
            let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
            for y in 0..src.height {
                for x in 0..src.width {
                    let l = direction((x as f32 + 0.5) / 256.0, (y as f32 + 0.5) / 128.0);
                    let nl = l.dot(n);
                    if nl <= 0.0 {
                        continue;
                    }
                    let h = (l + n).normalize();
                    let ct = h.dot(n);
                    let d = ct * ct * (a2 - 1.0) + 1.0;
                    let w = a2 / (PI * d * d) * nl * (1.0 - l.y * l.y).sqrt();
                    sum += texel(&src, x, y) * w;
                    wsum += w;
                }
            }
            let truth = sum / wsum;
            let (u, v) = uv_of(n);
            let got = bilinear(&levels[k as usize], u, v);
            let err = ((got - truth) / truth).abs().max_element();
            println!(
                "level {k} (roughness {:.2}): {got} vs {truth}, {:.1} %",
                level_roughness(k),
                err * 100.0
            );
            assert!(err < 0.03, "level {k}: {got} vs brute force {truth}");
        }
    }

    #[test]
    fn level_sizes_halve_down_to_a_grid_that_still_resolves_the_roughest_lobe() {
        let e = level_extents();
        assert_eq!(e.len(), ENV_SPECULAR_LEVELS as usize);
        assert_eq!(e[0], (BASE_WIDTH, BASE_WIDTH / 2));
        assert!(e.windows(2).all(|p| p[1].0 * 2 == p[0].0 && p[1].1 * 2 == p[0].1), "{e:?}");
        assert!(e.last().unwrap().0 >= 16, "{e:?}");
    }
}
