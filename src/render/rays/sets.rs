//! The microbenchmark's fixed ray sets and the ray-by-ray comparison of two
//! tracers. Primary rays go through the pixel centres of the scene camera;
//! shadow rays run from the primary hits to the first light; diffuse rays
//! leave the primary hits cosine-distributed about the geometric normal,
//! from a seeded hash of the ray index (the same set every run).

use anyhow::{bail, Result};
use glam::{DQuat, Vec3};

use super::{BenchRay, BenchResult};
use crate::gpu::origin::RenderOrigin;
use crate::scene::{Camera, LightKind, Scene};

/// Closest-hit rays run to "infinity" (as RAY_TMAX in the integrator).
pub const RAY_TMAX: f32 = 1e30;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    Primary,
    Shadow,
    Diffuse,
}

impl RayKind {
    pub const ALL: [RayKind; 3] = [RayKind::Primary, RayKind::Shadow, RayKind::Diffuse];

    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Shadow => "shadow",
            RayKind::Diffuse => "diffuse",
        }
    }

    /// Any-hit transmittance rays (trace_shadow) rather than closest hit.
    pub fn is_shadow(self) -> bool {
        self == RayKind::Shadow
    }
}

fn ray(o: Vec3, d: Vec3, tmax: f32) -> BenchRay {
    BenchRay { origin: o.to_array(), tmax, dir: d.to_array(), pad: 0 }
}

/// Pixels per ray-order tile: 4 x 2, so the 8 consecutive rays that one
/// llvmpipe subgroup (8 lanes) traces are neighbours in both directions.
pub const TILE: (u32, u32) = (4, 2);

/// Camera rays through the pixel centres of a `width` x `height` image
/// (the same directions as glsl/common/primary_hit.glsl `camera_ray_dir`),
/// in TILE-sized tiles row by row (partial tiles at the right and bottom
/// edges); the shadow and diffuse sets inherit the order.
pub fn primary_rays(camera: &Camera, origin: &RenderOrigin, width: u32, height: u32) -> Vec<BenchRay> {
    let (_, rot, _) = camera.world.to_scale_rotation_translation();
    let rot: DQuat = rot.normalize();
    let rot = rot.as_quat();
    let eye = origin.point(camera.position_f64());
    let f = 1.0 / (0.5 * camera.yfov).tan();
    let aspect = width as f32 / height as f32;
    let mut rays = Vec::with_capacity((width * height) as usize);
    let pixels = (0..height).step_by(TILE.1 as usize).flat_map(|ty| {
        (0..width).step_by(TILE.0 as usize).flat_map(move |tx| {
            (ty..(ty + TILE.1).min(height))
                .flat_map(move |y| (tx..(tx + TILE.0).min(width)).map(move |x| (x, y)))
        })
    });
    for (x, y) in pixels {
        let ndc_x = (x as f32 + 0.5) / width as f32 * 2.0 - 1.0;
        let ndc_y = (y as f32 + 0.5) / height as f32 * 2.0 - 1.0;
        let dv = Vec3::new(ndc_x * aspect / f, -ndc_y / f, -1.0);
        rays.push(ray(eye, (rot * dv).normalize(), RAY_TMAX));
    }
    rays
}

/// Shadow rays from every primary hit (`hits`: results of `primary`) to the
/// scene's first light; the light's own distance bounds point and spot rays.
pub fn shadow_rays(scene: &Scene, origin: &RenderOrigin, hits: &[BenchResult]) -> Result<Vec<BenchRay>> {
    let Some(light) = scene.lights.first() else {
        bail!("{}: the scene has no light, so there are no shadow rays to trace", scene.source.display())
    };
    let to_light = origin.point(light.position);
    Ok(hits
        .iter()
        .filter(|h| h.hit != 0)
        .filter_map(|h| {
            let o = Vec3::from_array(h.next);
            match light.kind {
                LightKind::Directional => Some(ray(o, -light.direction, RAY_TMAX)),
                LightKind::Point | LightKind::Spot { .. } => {
                    let v = to_light - o;
                    let dist = v.length();
                    // A hit exactly at the light has no direction to trace.
                    (dist > 0.0).then(|| ray(o, v / dist, dist * (1.0 - 1e-4)))
                }
            }
        })
        .collect())
}

/// PCG hash (Jarzynski & Olano 2020): a deterministic stream per ray index.
fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

fn unit(h: u32) -> f32 {
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Cosine-distributed bounce rays from every primary hit, from `seed`.
pub fn diffuse_rays(hits: &[BenchResult], seed: u32) -> Vec<BenchRay> {
    hits.iter()
        .enumerate()
        .filter(|(_, h)| h.hit != 0)
        .map(|(i, h)| {
            let n = Vec3::from_array(h.normal);
            let h1 = pcg(i as u32 ^ pcg(seed));
            let h2 = pcg(h1);
            let (u1, u2) = (unit(h1), unit(h2));
            // Malley's method: a uniform disk point lifted to the hemisphere.
            let r = u1.sqrt();
            let phi = std::f32::consts::TAU * u2;
            let (t, b) = n.any_orthonormal_pair();
            let z = (1.0 - u1).max(0.0).sqrt();
            let d = (t * (r * phi.cos()) + b * (r * phi.sin()) + n * z).normalize();
            ray(Vec3::from_array(h.next), d, RAY_TMAX)
        })
        .collect()
}

/// Largest relative difference of the two tracers' hit distances that
/// still counts as the same hit: both intersect in f32 after their own
/// object-space transforms.
pub const T_REL_BOUND: f32 = 1e-3;
/// Largest difference of the two tracers' shadow transmittance per channel.
pub const TRANSMITTANCE_BOUND: f32 = 1e-3;

/// Rays on which `a` and `b` disagree: hit versus miss (blocked versus
/// not, for shadow rays), hit distances further apart than `T_REL_BOUND`
/// of the distance, or transmittance further apart than
/// `TRANSMITTANCE_BOUND`. Returns the indices.
pub fn mismatches(kind: RayKind, a: &[BenchResult], b: &[BenchResult]) -> Vec<usize> {
    a.iter()
        .zip(b)
        .enumerate()
        .filter(|(_, (x, y))| {
            if (x.hit != 0) != (y.hit != 0) {
                return true;
            }
            if kind.is_shadow() {
                let (tx, ty) = (Vec3::from_array(x.next), Vec3::from_array(y.next));
                return (tx - ty).abs().max_element() > TRANSMITTANCE_BOUND;
            }
            x.hit != 0 && (x.t - y.t).abs() > T_REL_BOUND * x.t.max(y.t)
        })
        .map(|(i, _)| i)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(n: Vec3) -> BenchResult {
        BenchResult { hit: 1, normal: n.to_array(), ..Default::default() }
    }

    #[test]
    fn diffuse_rays_are_deterministic_unit_and_in_the_hemisphere() {
        let n = Vec3::new(0.3, -0.8, 0.52).normalize();
        let hits = vec![hit(n); 4096];
        let a = diffuse_rays(&hits, 7);
        assert_eq!(a.len(), 4096);
        let mut mean_cos = 0.0;
        for r in &a {
            let d = Vec3::from_array(r.dir);
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!(d.dot(n) >= -1e-6, "{d} below the surface");
            mean_cos += d.dot(n) as f64 / 4096.0;
        }
        // Cosine-weighted: E[cos] = 2/3 (uniform would give 1/2).
        assert!((mean_cos - 2.0 / 3.0).abs() < 0.02, "{mean_cos}");
        let b = diffuse_rays(&hits, 7);
        assert!(a.iter().zip(&b).all(|(x, y)| x.dir == y.dir));
        let c = diffuse_rays(&hits, 8);
        assert!(a.iter().zip(&c).any(|(x, y)| x.dir != y.dir));
    }

    /// Every pixel once, and each run of 8 rays inside the full tiles
    /// within one 4x2 block; 10 x 5 has partial tiles at both edges.
    #[test]
    fn primary_rays_cover_every_pixel_once_in_tiles() {
        let camera = Camera::look_at("t", Vec3::ZERO, Vec3::NEG_Z, std::f32::consts::FRAC_PI_2, 0.1);
        let (w, h) = (10u32, 5u32);
        let rays = primary_rays(&camera, &RenderOrigin(glam::DVec3::ZERO), w, h);
        assert_eq!(rays.len(), (w * h) as usize);
        // Invert the pixel-centre directions (yfov 90 degrees: f = 1).
        let pixel = |r: &BenchRay| {
            let d = Vec3::from_array(r.dir);
            let ndc_x = d.x / -d.z / (w as f32 / h as f32);
            let ndc_y = -d.y / -d.z;
            let x = ((ndc_x + 1.0) * 0.5 * w as f32 - 0.5).round() as u32;
            let y = ((ndc_y + 1.0) * 0.5 * h as f32 - 0.5).round() as u32;
            (x, y)
        };
        let px: Vec<(u32, u32)> = rays.iter().map(pixel).collect();
        let mut seen = vec![false; (w * h) as usize];
        for &(x, y) in &px {
            assert!(x < w && y < h, "({x}, {y}) outside the image");
            assert!(!std::mem::replace(&mut seen[(y * w + x) as usize], true), "({x}, {y}) twice");
        }
        // The first tile row: 4x2, 4x2, then the 2x2 remainder.
        assert_eq!(&px[..8], &[(0, 0), (1, 0), (2, 0), (3, 0), (0, 1), (1, 1), (2, 1), (3, 1)]);
        assert_eq!(&px[16..20], &[(8, 0), (9, 0), (8, 1), (9, 1)]);
        for run in px[..16].chunks(8) {
            let (x0, y0) = run[0];
            assert!(run.iter().all(|&(x, y)| x - x0 < TILE.0 && y - y0 < TILE.1), "{run:?}");
        }
    }

    #[test]
    fn mismatch_rules() {
        let miss = BenchResult::default();
        let at = |t: f32| BenchResult { hit: 1, t, ..Default::default() };
        assert!(mismatches(RayKind::Primary, &[at(10.0)], &[at(10.005)]).is_empty());
        assert_eq!(mismatches(RayKind::Primary, &[at(10.0)], &[at(10.2)]), vec![0]);
        assert_eq!(mismatches(RayKind::Diffuse, &[miss, at(1.0)], &[miss, miss]), vec![1]);
        let tr = |v: f32| BenchResult { next: [v; 3], ..Default::default() };
        assert!(mismatches(RayKind::Shadow, &[tr(0.5)], &[tr(0.5004)]).is_empty());
        assert_eq!(mismatches(RayKind::Shadow, &[tr(0.5)], &[tr(0.6)]), vec![0]);
    }
}
