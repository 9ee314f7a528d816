//! Images and the code that makes them, in process on lavapipe: every
//! backend, analytic scenes, goldens, the frame layer, acceleration data.
//! The integration tests live in a few crates (cli, frames, render, report,
//! fuzz_loader) so the program is linked a handful of times, not once per
//! file; fuzz_loader keeps its own because it installs a global allocator.

#[path = "../common/mod.rs"]
mod common;

mod alpha_lod;
mod ambient_visibility;
mod analytic_lighting;
mod animation;
mod antialias;
mod backends;
mod budget;
mod budget_fallback;
mod clearcoat;
mod compute_top_level;
mod culling;
mod device;
mod emitters;
mod error_paths;
mod extreme_radiance;
mod far_from_origin;
mod frame;
mod ibl;
mod lbvh;
mod memory;
mod models;
mod occlusion;
mod one_shot;
mod orbit;
mod primary_visibility;
mod prt;
mod ray_budget;
mod rays;
mod raytracing;
mod readback;
mod shading_closed_form;
mod shared_layout;
mod skinning;
mod speckles;
mod specular_extension;
mod texture_transform;
mod tonemap;
mod vulkan12;
mod watertight;
