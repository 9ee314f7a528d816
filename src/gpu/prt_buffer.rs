//! Diffuse PRT on the GPU: the placeholder bound when no transfer is (the
//! transfer itself is packed by `prt::pack`, a layer above), and the
//! environment's radiance coefficients as the frame uniform holds them.

use anyhow::Result;
use ash::vk;

use super::shared::{PRT_HEADER_WORDS, SH_PRT_MAX_COEFFS};
use crate::scene::sh::ShCoeffs;
use crate::scene::Environment;
use crate::vk::memory::Buffer;
use crate::vk::Context;

const _: () =
    assert!(SH_PRT_MAX_COEFFS as usize == crate::scene::sh::MAX_BANDS * crate::scene::sh::MAX_BANDS);

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
