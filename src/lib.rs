//! Hybrid rasterization + ray-tracing renderer on Vulkan (ash).
//!
//! Data flow of a frame (see DESIGN.md): `scene` (CPU) -> `gpu` (one copy of
//! the geometry on the GPU) -> `accel` (acceleration structures) -> `render`
//! (the frame's passes: G-buffer or primary rays, direct, specular,
//! composite, tone map) -> PNG / present. `vk` holds the Vulkan plumbing.
//!
//! Layers, lowest first: `vk`, `scene` (no GPU code), `gpu`, `accel`,
//! `render`, then `app`, `report` and `viewer`. A layer imports only the ones below.
//! `par` (a parallel map) sits below them all.

pub mod accel;
pub mod app;
pub mod gpu;
pub mod metrics;
pub mod par;
pub mod prt;
pub mod render;
pub mod report;
pub mod scene;
pub mod viewer;
pub mod vk;
