//! Value checks shared by the conversions: finite, non-negative, within
//! [0, 1], unit vectors; each error names the key.

use anyhow::{ensure, Context, Result};
use glam::{DVec3, Vec3};

pub(super) fn finite(v: f32, what: &str) -> Result<f32> {
    ensure!(v.is_finite(), "{what} must be finite");
    Ok(v)
}

pub(super) fn finite3(v: [f32; 3], what: &str) -> Result<Vec3> {
    ensure!(v.iter().all(|c| c.is_finite()), "{what} must be finite");
    Ok(Vec3::from(v))
}

/// A placement (position, translation): kept in f64, like the scene's.
pub(super) fn finite3_f64(v: [f64; 3], what: &str) -> Result<DVec3> {
    ensure!(v.iter().all(|c| c.is_finite()), "{what} must be finite");
    Ok(DVec3::from(v))
}

pub(super) fn non_negative(v: f32, what: &str) -> Result<f32> {
    ensure!(v.is_finite() && v >= 0.0, "{what} must be finite and >= 0 (got {v})");
    Ok(v)
}

pub(super) fn non_negative3(v: [f32; 3], what: &str) -> Result<Vec3> {
    ensure!(v.iter().all(|c| c.is_finite() && *c >= 0.0), "{what} components must be finite and >= 0");
    Ok(Vec3::from(v))
}

pub(super) fn unit_interval(v: f32, what: &str) -> Result<f32> {
    ensure!((0.0..=1.0).contains(&v), "{what} must be within [0, 1] (got {v})");
    Ok(v)
}

pub(super) fn unit(v: [f32; 3], what: &str) -> Result<Vec3> {
    finite3(v, what)?.try_normalize().with_context(|| format!("{what} must not be zero"))
}
