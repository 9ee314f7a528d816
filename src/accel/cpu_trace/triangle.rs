//! The watertight ray/triangle test of Woop, Benthin and Wald
//! ("Watertight Ray/Triangle Intersection", JCGT 2(1), 2013), as the
//! compute tracer runs it (glsl/trace/compute.glsl); conventions in mod.rs.

use glam::Vec3;

/// Per-ray constants of the watertight test: the axis permutation
/// (`kz` = largest |dir| component, `kx`, `ky` the next two cyclically,
/// swapped when `dir[kz] < 0` to keep the winding) and the shear
/// `S = (dir[kx] / dir[kz], dir[ky] / dir[kz], 1 / dir[kz])` that maps the
/// ray onto +z.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    pub origin: Vec3,
    pub k: [usize; 3],
    pub shear: Vec3,
}

impl WatertightRay {
    pub fn new(origin: Vec3, dir: Vec3) -> WatertightRay {
        let a = dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        // A zero direction gives NaN/inf shears; every test then fails its
        // final `0 < t < tmax` check (NaN compares false): no hit, no NaN out.
        let shear = Vec3::new(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        WatertightRay { origin, k: [kx, ky, kz], shear }
    }

    /// `Some((t, u, v))` when the ray hits the triangle at `0 < t < tmax`
    /// (either winding); `u`, `v` weigh `p1` and `p2`. Degenerate triangles
    /// and rays in the triangle's plane give `det == 0`: no hit.
    pub fn intersect(&self, p0: Vec3, p1: Vec3, p2: Vec3, tmax: f32) -> Option<(f32, f32, f32)> {
        let [kx, ky, kz] = self.k;
        let s = self.shear;
        // Translate to the ray origin, then shear so the ray runs along +z.
        let (a, b, c) = (p0 - self.origin, p1 - self.origin, p2 - self.origin);
        let (ax, ay) = (a[kx] - s.x * a[kz], a[ky] - s.y * a[kz]);
        let (bx, by) = (b[kx] - s.x * b[kz], b[ky] - s.y * b[kz]);
        let (cx, cy) = (c[kx] - s.x * c[kz], c[ky] - s.y * c[kz]);
        // Scaled barycentrics (2D edge functions): U weighs p0, V p1, W p2.
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // The paper's fallback: an edge function that rounds to exactly 0 is
        // recomputed in double precision (products of floats are exact
        // there), so the sign of a near-edge ray is decided consistently.
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let d = |p: f32, q: f32, r: f32, t: f32| (p as f64 * q as f64 - r as f64 * t as f64) as f32;
            u = d(cx, by, cy, bx);
            v = d(ax, cy, ay, cx);
            w = d(bx, ay, by, ax);
        }
        // Mixed signs: outside. Zeros count as inside for both neighbours,
        // so a ray through a shared edge or vertex is never lost.
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || det.is_nan() {
            return None;
        }
        // Scaled hit distance; compare against 0 and tmax * det with the
        // sign of det folded in (no division before the hit is known).
        let (az, bz, cz) = (s.z * a[kz], s.z * b[kz], s.z * c[kz]);
        let t_scaled = u * az + v * bz + w * cz;
        let inside = if det > 0.0 {
            t_scaled > 0.0 && t_scaled < tmax * det
        } else {
            t_scaled < 0.0 && t_scaled > tmax * det
        };
        if !inside {
            return None;
        }
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        // Rounding of the division can still land on 0 or tmax.
        if !(t > 0.0 && t < tmax) {
            return None;
        }
        // Not in the paper: a zero-area triangle can pass when the ray runs exactly through one of its
        // points (the shear rounds its projection off the line); its normal would be zero (NaN normalised).
        let n = (p1 - p0).cross(p2 - p0);
        let nn = n.dot(n);
        if nn == 0.0 || nn.is_nan() {
            return None;
        }
        Some((t, v * inv, w * inv))
    }
}

/// [`WatertightRay::intersect`] for a single triangle.
pub fn intersect_triangle(origin: Vec3, dir: Vec3, tri: &[Vec3; 3], tmax: f32) -> Option<(f32, f32, f32)> {
    WatertightRay::new(origin, dir).intersect(tri[0], tri[1], tri[2], tmax)
}
