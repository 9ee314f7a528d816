//! The sRGB transfer function on the CPU, the mirror of glsl/common/srgb.glsl (IEC 61966-2-1, exact piecewise
//! form): for filtering display values (supersampling) and for the report's tone mapper.

/// sRGB-encoded [0, 1] to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c > 0.04045 {
        ((c + 0.055) / 1.055).powf(2.4)
    } else {
        c / 12.92
    }
}

/// Linear to sRGB-encoded, clamped to [0, 1] (non-finite: 0).
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.0 };
    if c > 0.0031308 {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    } else {
        c * 12.92
    }
}
