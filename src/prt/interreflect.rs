//! Sloan et al. 2002's interreflection passes: bounce b adds, for every
//! direction whose ray hits a front face of the static geometry, the hit
//! point's albedo / pi times its interpolated bounce-(b-1) transfer (the
//! radiance leaving a Lambertian point is albedo / pi times its
//! irradiance). Bounce 0 is the shadowed transfer. RGB results.

use std::f64::consts::PI;

use super::transfer::{per_vertex, Occluders, SampleSet};
use super::WorldVertex;
use crate::scene::sh::MAX_BANDS;

/// Shadowed transfer `direct` (monochrome) plus `bounces` interreflection
/// passes, as RGB transfer (bands² × 3 floats a vertex).
pub(crate) fn bounces(
    verts: &[WorldVertex],
    s: &SampleSet,
    occ: &Occluders,
    direct: &[f32],
    bounces: u32,
    rays: &mut u64,
) -> Vec<f32> {
    let k = s.coeffs;
    // Bounce 0 as RGB.
    let mut total: Vec<f32> = direct.iter().flat_map(|&t| [t; 3]).collect();
    let mut prev = total.clone();
    for b in 1..=bounces {
        let (this, traced) = per_vertex(verts.len(), k * 3, &format!("bounce {b}"), |v, out| {
            let wv = &verts[v];
            let mut acc = [[0.0f64; 3]; MAX_BANDS * MAX_BANDS];
            let mut traced = 0u64;
            for d in &s.dirs {
                let c = wv.n.dot(*d);
                if c <= 0.0 {
                    continue;
                }
                traced += 1;
                // Back faces (inside a closed mesh) block but do not reflect.
                let Some((t, b1, b2, true)) = occ.trace(wv, *d) else { continue };
                let [i0, i1, i2] = occ.verts[t as usize];
                let w = [1.0 - b1 as f64 - b2 as f64, b1 as f64, b2 as f64];
                let rho = occ.albedo[t as usize];
                for (kk, a) in acc.iter_mut().enumerate().take(k) {
                    for ch in 0..3 {
                        let at = |vi: u32| prev[(vi as usize * k + kk) * 3 + ch] as f64;
                        let tq = w[0] * at(i0) + w[1] * at(i1) + w[2] * at(i2);
                        a[ch] += c * rho[ch] as f64 / PI * tq;
                    }
                }
            }
            for (kk, a) in acc.iter().enumerate().take(k) {
                for ch in 0..3 {
                    out[kk * 3 + ch] = (a[ch] * s.weight) as f32;
                }
            }
            traced
        });
        *rays += traced;
        for (t, x) in total.iter_mut().zip(&this) {
            *t += x;
        }
        prev = this;
    }
    total
}
