//! Hybrid rasterization + ray-tracing renderer on Vulkan (ash).
//!
//! Data flow of a frame (see DESIGN.md): `scene` (CPU) -> `render::gpu_scene`
//! (one copy of the geometry on the GPU) -> G-buffer -> deferred lighting ->
//! tone map -> PNG / present. `vk` holds the Vulkan plumbing every pass uses.

pub mod accel;
pub mod app;
pub mod metrics;
pub mod render;
pub mod scene;
pub mod viewer;
pub mod vk;
