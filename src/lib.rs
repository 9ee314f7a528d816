//! Hybrid rasterization + ray-tracing renderer on Vulkan (ash).
//!
//! Data flow of a frame (see DESIGN.md): `scene` (CPU) -> `gpu` (one copy of the geometry on the GPU)
//! -> `accel` (acceleration structures) -> `render` (the frame's passes: G-buffer or primary rays,
//! direct, specular, composite, tone map) -> PNG / present. `vk` holds the Vulkan plumbing.
//!
//! The layers, lowest first, are listed once in `layering.rs` (`LAYERS`): a module imports only those
//! below it, and no import cycle leaves a folder; that file's tests read every file's paths.

pub mod accel;
pub mod app;
pub mod csv;
pub mod disk_cache;
pub mod gpu;
pub mod image_diff;
#[cfg(test)]
mod layering;
pub mod par;
pub mod progress;
pub mod prt;
pub mod render;
pub mod report;
pub mod scene;
pub mod viewer;
pub mod vk;
