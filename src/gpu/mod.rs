//! The scene's one copy on the GPU (descriptor set 0: geometry, materials,
//! instances, lights, textures, environment) and the host/shader shared
//! types. Sits between `vk` and the layers that use the GPU scene (`accel`,
//! `render`): it imports only `vk` and `scene`.

pub mod clusters;
mod draw;
pub mod emitters;
pub mod env_prefilter;
pub mod env_sampling;
pub mod env_sh;
pub mod environment;
pub mod material;
mod memory;
pub mod origin;
pub mod prt_buffer;
pub mod scene;
pub mod shadow_map;
pub mod shared;
pub mod split_sum;
pub mod types;

pub use memory::SceneMemory;
pub use scene::{Draw, GpuScene, PrimitiveRange};
