//! The options that pick and set up the Vulkan device, global to every
//! command, and the one place they become [`GpuOptions`].

use clap::Args;

use super::GpuOptions;
use crate::vk::DeviceSelector;

#[derive(Args)]
pub struct GpuArgs {
    /// Enable VK_LAYER_KHRONOS_validation; any validation error makes the
    /// command fail. Also on with HYBRID_RT_VALIDATION=1.
    #[arg(long, global = true)]
    pub validation: bool,
    /// With --validation: also run synchronization validation.
    #[arg(long, global = true)]
    pub sync_validation: bool,
    /// Device: index from `info`, a name substring, or "auto" (prefers a discrete GPU).
    #[arg(long, global = true, default_value = "auto")]
    pub device: String,
    /// Do not enable any ray-tracing extension even if the device has them.
    #[arg(long, global = true)]
    pub no_rt: bool,
    /// Do not enable VK_KHR_ray_query even if the device has it: the path of
    /// drivers that offer only the ray-tracing pipeline.
    #[arg(long, global = true)]
    pub no_ray_query: bool,
    /// Highest Vulkan API version to use (1.2 or 1.3): 1.2 takes the path a
    /// 1.2 device takes (RenderDoc 1.24 shows lavapipe as one), the 1.3
    /// features through their extensions.
    #[arg(long, global = true, value_parser = parse_vulkan_api)]
    pub vulkan_api: Option<u32>,
    /// Log level (error, warn, info, debug, trace); RUST_LOG overrides.
    #[arg(long, global = true, default_value = "info")]
    pub log: String,
}

impl GpuArgs {
    /// The device options, validation also on with HYBRID_RT_VALIDATION=1.
    pub fn options(&self) -> GpuOptions {
        let env_validation = std::env::var("HYBRID_RT_VALIDATION").is_ok_and(|v| v != "0" && !v.is_empty());
        GpuOptions {
            validation: self.validation || self.sync_validation || env_validation,
            sync_validation: self.sync_validation,
            device: self.device.parse::<DeviceSelector>().unwrap_or_default(),
            disable_ray_tracing: self.no_rt,
            disable_ray_query: self.no_ray_query,
            disable_trace_rays_indirect: false,
            disable_subgroup_arithmetic: false,
            max_api_version: self.vulkan_api,
            capture_frame: None,
        }
    }
}

fn parse_vulkan_api(s: &str) -> Result<u32, String> {
    match s {
        "1.2" => Ok(ash::vk::API_VERSION_1_2),
        "1.3" => Ok(ash::vk::API_VERSION_1_3),
        _ => Err(format!("'{s}' is not 1.2 or 1.3")),
    }
}
