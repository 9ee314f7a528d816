//! Values shared with the shaders, from their one source
//! (`shared_values.rs`, which build.rs also turns into
//! `generated/shared.glsl`). `GLSL_HEADER` is that header as the shaders
//! were compiled with, so a test can check the two sides agree.

macro_rules! shared {
    (@ty id) => { u32 };
    (@ty uint) => { u32 };
    (@ty float) => { f32 };
    ($($kind:ident $name:ident = $value:expr;)*) => {
        $(pub const $name: shared!(@ty $kind) = $value;)*
        /// Every shared value by name, as f64 (for the drift test).
        pub const ALL: &[(&str, f64)] = &[$((stringify!($name), $value as f64)),*];
    };
}

include!("shared_values.rs");

/// The generated GLSL header the shaders include.
pub const GLSL_HEADER: &str = include_str!(concat!(env!("OUT_DIR"), "/generated/shared.glsl"));
