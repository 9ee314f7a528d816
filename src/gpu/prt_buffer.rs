//! Diffuse PRT on the GPU: the per-vertex transfer of src/prt packed into
//! one storage buffer (layout: shared_values.rs SCENE_PRT), and the
//! environment's radiance coefficients as the frame uniform holds them.

use anyhow::Result;
use ash::vk;

use super::shared::{PRT_HEADER_WORDS, PRT_NO_VERTEX, SH_PRT_MAX_COEFFS};
use crate::prt::PrtTransfer;
use crate::scene::sh::ShCoeffs;
use crate::scene::Environment;
use crate::vk::memory::Buffer;
use crate::vk::Context;

const _: () =
    assert!(SH_PRT_MAX_COEFFS as usize == crate::scene::sh::MAX_BANDS * crate::scene::sh::MAX_BANDS);

/// Header, per-instance first vertex, transfer floats (as bits).
pub fn pack(t: &PrtTransfer) -> Vec<u32> {
    let n = t.first_vertex.len();
    let mut w = Vec::with_capacity(PRT_HEADER_WORDS as usize + n + t.data.len());
    w.extend_from_slice(&[t.coeffs() as u32, t.channels() as u32, n as u32, 0]);
    w.extend(t.first_vertex.iter().map(|f| f.unwrap_or(PRT_NO_VERTEX)));
    w.extend(t.data.iter().map(|f| f.to_bits()));
    w
}

/// The buffer bound without a prt ambient mode: no instances.
pub fn placeholder(ctx: &Context) -> Result<Buffer> {
    Buffer::with_data(
        ctx,
        "prt transfer (none)",
        bytemuck::cast_slice(&[0u32; PRT_HEADER_WORDS as usize]),
        vk::BufferUsageFlags::STORAGE_BUFFER,
    )
}

/// Radiance coefficients L_lm for the frame uniform: rotated by the
/// environment's rotation (exact, no re-projection) and scaled by its
/// intensity; not convolved (the transfer holds the cosine).
pub fn radiance_uniform(radiance: &ShCoeffs, env: &Environment) -> [[f32; 4]; SH_PRT_MAX_COEFFS as usize] {
    let l = radiance.rotated_y(env.rotation as f64);
    let s = env.intensity as f64;
    let mut out = [[0.0f32; 4]; SH_PRT_MAX_COEFFS as usize];
    for (o, c) in out.iter_mut().zip(l.coeffs()) {
        *o = [(c[0] * s) as f32, (c[1] * s) as f32, (c[2] * s) as f32, 0.0];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prt::{PrtMode, PrtSettings};

    #[test]
    fn pack_layout() {
        let t = PrtTransfer {
            settings: PrtSettings { bands: 2, ..PrtSettings::new(PrtMode::Interreflected) },
            first_vertex: vec![Some(0), None, Some(1)],
            data: (0..24).map(|i| i as f32).collect(),
            rays: 0,
        };
        let w = pack(&t);
        assert_eq!(&w[..7], &[4, 3, 3, 0, 0, PRT_NO_VERTEX, 1]);
        assert_eq!(w.len(), 7 + 24);
        assert_eq!(f32::from_bits(w[7 + 12 + 5]), 17.0);
    }
}
