//! The environment map's pixels, in their own file so `sh` and
//! `env_layout` take them without importing the scene module above them.

/// Linear RGB float image (equirectangular environment).
#[derive(Clone, Debug)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<f32>,
}
