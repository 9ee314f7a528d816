//! Physical-device choice, the capability report and the logical device with
//! the feature chain the renderer needs.

use std::ffi::CStr;

use anyhow::{bail, Context as _, Result};
use ash::{khr, vk};

/// What a physical device offers, as far as this renderer cares.
#[derive(Clone, Debug)]
pub struct Capabilities {
    pub index: usize,
    pub name: String,
    pub device_type: vk::PhysicalDeviceType,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: u32,
    pub acceleration_structure: bool,
    pub ray_query: bool,
    pub ray_tracing_pipeline: bool,
    pub timestamp_period_ns: f32,
    pub timestamps: bool,
    pub graphics_queue_family: u32,
    pub limits: super::limits::Limits,
    /// Why the device is unusable, if it is.
    pub unusable: Option<String>,
}

impl Capabilities {
    pub fn api_string(&self) -> String {
        format!(
            "{}.{}.{}",
            vk::api_version_major(self.api_version),
            vk::api_version_minor(self.api_version),
            vk::api_version_patch(self.api_version)
        )
    }

    /// Human-readable multi-line report (the `info` command).
    pub fn report(&self) -> String {
        let yn = |b: bool| if b { "yes" } else { "no" };
        let mut s = format!(
            "device {}: {} ({:?})\n  driver: {} {}\n  Vulkan API: {}\n  acceleration structures: {}\n  ray query: {}\n  ray-tracing pipeline: {}\n  timestamps: {} ({} ns/tick)\n",
            self.index,
            self.name,
            self.device_type,
            self.driver_name,
            self.driver_info,
            self.api_string(),
            yn(self.acceleration_structure),
            yn(self.ray_query),
            yn(self.ray_tracing_pipeline),
            yn(self.timestamps),
            self.timestamp_period_ns
        );
        if let Some(why) = &self.unusable {
            s.push_str(&format!("  unusable: {why}\n"));
        }
        s
    }
}

fn has_ext(exts: &[vk::ExtensionProperties], name: &CStr) -> bool {
    exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name))
}

pub fn query_capabilities(instance: &ash::Instance, pd: vk::PhysicalDevice, index: usize) -> Capabilities {
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let props = props2.properties;
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();

    let mut asf = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut rqf = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut rtf = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
    let has_as = has_ext(&exts, khr::acceleration_structure::NAME)
        && has_ext(&exts, khr::deferred_host_operations::NAME);
    let has_rq = has_ext(&exts, khr::ray_query::NAME);
    let has_rt = has_ext(&exts, khr::ray_tracing_pipeline::NAME);
    {
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v12).push_next(&mut v13);
        if has_as {
            f2 = f2.push_next(&mut asf);
        }
        if has_rq {
            f2 = f2.push_next(&mut rqf);
        }
        if has_rt {
            f2 = f2.push_next(&mut rtf);
        }
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    }

    let base = unsafe { instance.get_physical_device_features(pd) };
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let gfx = families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE));
    let timestamps = gfx.map(|g| families[g].timestamp_valid_bits > 0).unwrap_or(false)
        && props.limits.timestamp_period > 0.0;

    let mut unusable = None;
    if props.api_version < vk::API_VERSION_1_3 {
        unusable = Some("Vulkan 1.3 required".to_string());
    } else if gfx.is_none() {
        unusable = Some("no graphics+compute queue".to_string());
    } else if base.geometry_shader == 0 {
        // gl_PrimitiveID in the G-buffer fragment shader needs it.
        unusable = Some("geometryShader feature required (fragment gl_PrimitiveID)".to_string());
    } else if v13.dynamic_rendering == 0 || v13.synchronization2 == 0 {
        unusable = Some("dynamic rendering and synchronization2 required".to_string());
    } else if v12.buffer_device_address == 0
        || v12.descriptor_indexing == 0
        || v12.runtime_descriptor_array == 0
        || v12.descriptor_binding_partially_bound == 0
        || v12.shader_sampled_image_array_non_uniform_indexing == 0
        || v12.scalar_block_layout == 0
    {
        unusable = Some("buffer device address, descriptor indexing and scalar layout required".to_string());
    }

    let as_ok = has_as && asf.acceleration_structure != 0 && v12.buffer_device_address != 0;
    Capabilities {
        index,
        name: props.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default(),
        device_type: props.device_type,
        driver_name: driver
            .driver_name_as_c_str()
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_default(),
        driver_info: driver
            .driver_info_as_c_str()
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_default(),
        api_version: props.api_version,
        acceleration_structure: as_ok,
        ray_query: as_ok && has_rq && rqf.ray_query != 0,
        ray_tracing_pipeline: as_ok && has_rt && rtf.ray_tracing_pipeline != 0,
        timestamp_period_ns: props.limits.timestamp_period,
        timestamps,
        graphics_queue_family: gfx.unwrap_or(0) as u32,
        limits: super::limits::Limits::query(instance, pd, has_as),
        unusable,
    }
}

/// How to pick among several physical devices.
#[derive(Clone, Debug, Default)]
pub enum DeviceSelector {
    /// Discrete GPU first, then integrated, virtual, CPU.
    #[default]
    Auto,
    Index(usize),
    NameContains(String),
}

impl std::str::FromStr for DeviceSelector {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.parse::<usize>() {
            Ok(i) => DeviceSelector::Index(i),
            Err(_) if s.eq_ignore_ascii_case("auto") => DeviceSelector::Auto,
            Err(_) => DeviceSelector::NameContains(s.to_string()),
        })
    }
}

fn type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

pub fn enumerate(instance: &ash::Instance) -> Result<Vec<(vk::PhysicalDevice, Capabilities)>> {
    let pds = unsafe { instance.enumerate_physical_devices() }.context("vkEnumeratePhysicalDevices")?;
    Ok(pds.into_iter().enumerate().map(|(i, pd)| (pd, query_capabilities(instance, pd, i))).collect())
}

pub fn select(
    devices: &[(vk::PhysicalDevice, Capabilities)],
    selector: &DeviceSelector,
) -> Result<(vk::PhysicalDevice, Capabilities)> {
    if devices.is_empty() {
        bail!("no Vulkan device found (install mesa-vulkan-drivers for lavapipe, or a GPU driver)");
    }
    let chosen = match selector {
        DeviceSelector::Index(i) => devices
            .get(*i)
            .with_context(|| format!("device index {i} out of range ({} devices)", devices.len()))?,
        DeviceSelector::NameContains(s) => {
            let needle = s.to_lowercase();
            devices
                .iter()
                .find(|(_, c)| c.name.to_lowercase().contains(&needle))
                .with_context(|| format!("no device name contains '{s}'"))?
        }
        DeviceSelector::Auto => devices
            .iter()
            .filter(|(_, c)| c.unusable.is_none())
            .min_by_key(|(_, c)| (type_rank(c.device_type), c.index))
            .with_context(|| {
                let why: Vec<_> = devices
                    .iter()
                    .map(|(_, c)| format!("{}: {}", c.name, c.unusable.as_deref().unwrap_or("?")))
                    .collect();
                format!("no usable Vulkan device: {}", why.join("; "))
            })?,
    };
    if let Some(why) = &chosen.1.unusable {
        bail!("device '{}' is not usable: {why}", chosen.1.name);
    }
    Ok(chosen.clone())
}

/// Which ray-tracing extensions to enable on the logical device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RtEnables {
    pub acceleration_structure: bool,
    pub ray_query: bool,
    pub ray_tracing_pipeline: bool,
}

pub fn create_device(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    caps: &Capabilities,
    rt: RtEnables,
    swapchain: bool,
) -> Result<ash::Device> {
    let prio = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(caps.graphics_queue_family)
        .queue_priorities(&prio)];

    let mut exts: Vec<*const std::ffi::c_char> = Vec::new();
    if swapchain {
        exts.push(khr::swapchain::NAME.as_ptr());
    }
    if rt.acceleration_structure {
        exts.push(khr::acceleration_structure::NAME.as_ptr());
        exts.push(khr::deferred_host_operations::NAME.as_ptr());
    }
    if rt.ray_query {
        exts.push(khr::ray_query::NAME.as_ptr());
    }
    if rt.ray_tracing_pipeline {
        exts.push(khr::ray_tracing_pipeline::NAME.as_ptr());
    }

    let base = vk::PhysicalDeviceFeatures::default().geometry_shader(true);
    let mut v11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default()
        .buffer_device_address(true)
        .descriptor_indexing(true)
        .runtime_descriptor_array(true)
        .descriptor_binding_partially_bound(true)
        .descriptor_binding_variable_descriptor_count(true)
        .shader_sampled_image_array_non_uniform_indexing(true)
        .shader_storage_buffer_array_non_uniform_indexing(true)
        .scalar_block_layout(true)
        .host_query_reset(true);
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true)
        .maintenance4(true)
        .shader_demote_to_helper_invocation(true);
    let mut asf = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
    let mut rqf = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
    let mut rtf = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default().ray_tracing_pipeline(true);

    let mut f2 = vk::PhysicalDeviceFeatures2::default()
        .features(base)
        .push_next(&mut v11)
        .push_next(&mut v12)
        .push_next(&mut v13);
    if rt.acceleration_structure {
        f2 = f2.push_next(&mut asf);
    }
    if rt.ray_query {
        f2 = f2.push_next(&mut rqf);
    }
    if rt.ray_tracing_pipeline {
        f2 = f2.push_next(&mut rtf);
    }
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&exts)
        .push_next(&mut f2);
    unsafe { instance.create_device(pd, &info, None) }.context("vkCreateDevice failed")
}
