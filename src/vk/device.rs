//! Physical-device choice, the capability report and the logical device with
//! the feature chain the renderer needs.

use std::ffi::CStr;

use anyhow::{bail, Context as _, Result};
use ash::{ext, khr, vk};

use super::features::{self, FeaturePath};

/// What a physical device offers, as far as this renderer cares.
#[derive(Clone, Debug)]
pub struct Capabilities {
    pub index: usize,
    pub name: String,
    pub device_type: vk::PhysicalDeviceType,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: u32,
    /// The version the device is used at: the lower of `api_version` and
    /// the instance's (RenderDoc 1.24 reports lavapipe as 1.2.0).
    pub used_api_version: u32,
    /// bufferDeviceAddress: enabled when offered; acceleration structures
    /// need it, the compute backend does not.
    pub buffer_device_address: bool,
    /// How the 1.3 features are reached (core, or 1.2 + extensions); `None`
    /// when neither works (then `unusable` says why).
    pub feature_path: Option<FeaturePath>,
    pub acceleration_structure: bool,
    pub ray_query: bool,
    pub ray_tracing_pipeline: bool,
    /// rayTracingPipelineTraceRaysIndirect: a compacted pass launches its
    /// ray-generation shader over its listed pixels (render/passes/compacted.rs).
    pub trace_rays_indirect: bool,
    pub timestamp_period_ns: f32,
    pub timestamps: bool,
    /// Subgroup ballot and broadcast in compute shaders: the compute tracer's packet traversal
    /// (glsl/trace/compute_packet.glsl) needs them.
    pub subgroup_ops: bool,
    /// Subgroup arithmetic (add, min, max) with ballot in compute shaders: the `heuristic` pass reduces
    /// its per-object statistics per subgroup (glsl/heuristic.comp); without, per tile in shared memory.
    pub subgroup_arithmetic: bool,
    /// multiDrawIndirect and drawIndirectFirstInstance: the occlusion-culled
    /// G-buffer (render/occlusion.rs) draws clusters that way.
    pub multi_draw_indirect: bool,
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

    /// "1.4.305", or "1.4.305 used as 1.2" when the instance asks for less.
    pub fn api_used_string(&self) -> String {
        let minor = |v: u32| (vk::api_version_major(v), vk::api_version_minor(v));
        if minor(self.used_api_version) == minor(self.api_version) {
            return self.api_string();
        }
        let (major, minor) = minor(self.used_api_version);
        format!("{} used as {major}.{minor}", self.api_string())
    }

    /// "Vulkan 1.3 core", "Vulkan 1.2 + extensions ..." or "none".
    pub fn feature_path_string(&self) -> String {
        self.feature_path.as_ref().map_or_else(|| "none".to_string(), FeaturePath::describe)
    }

    /// Human-readable multi-line report (the `info` command).
    pub fn report(&self) -> String {
        let yn = |b: bool| if b { "yes" } else { "no" };
        let mut s = format!(
            "device {}: {} ({:?})\n  driver: {} {}\n  Vulkan API: {}\n  1.3 features: {}\n  acceleration structures: {}\n  ray query: {}\n  ray-tracing pipeline: {}\n  timestamps: {} ({} ns/tick)\n",
            self.index,
            self.name,
            self.device_type,
            self.driver_name,
            self.driver_info,
            self.api_string(),
            self.feature_path_string(),
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

/// What device `pd` offers when used through an instance of API version `instance_api`.
pub fn query_capabilities(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    index: usize,
    instance_api: u32,
) -> Capabilities {
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver).push_next(&mut subgroup);
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let props = props2.properties;
    let ops = vk::SubgroupFeatureFlags::BASIC | vk::SubgroupFeatureFlags::BALLOT;
    let compute = subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE);
    let subgroup_ops = compute && subgroup.supported_operations.contains(ops);
    let subgroup_arithmetic =
        subgroup_ops && subgroup.supported_operations.contains(vk::SubgroupFeatureFlags::ARITHMETIC);
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    // What a layer lets through differs from the driver (RenderDoc hides
    // what it cannot capture): `--log debug` lists it.
    log::debug!(
        "device {index}: API {}.{}, extensions {}",
        vk::api_version_major(props.api_version),
        vk::api_version_minor(props.api_version),
        exts.iter()
            .filter_map(|e| e.extension_name_as_c_str().ok().map(|n| n.to_string_lossy()))
            .collect::<Vec<_>>()
            .join(" ")
    );

    let mut asf = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut rqf = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut rtf = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let has_as = has_ext(&exts, khr::acceleration_structure::NAME)
        && has_ext(&exts, khr::deferred_host_operations::NAME);
    let has_rq = has_ext(&exts, khr::ray_query::NAME);
    let has_rt = has_ext(&exts, khr::ray_tracing_pipeline::NAME);
    {
        // Vulkan12Features is valid on 1.2; the 1.3 ones are queried by
        // features::choose (VkPhysicalDeviceVulkan13Features is not, there).
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v12);
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

    let used_api_version = props.api_version.min(instance_api);
    let feature_path = features::choose(instance, pd, used_api_version, &exts);
    let mut unusable = None;
    if let Err(why) = &feature_path {
        unusable = Some(why.clone());
    } else if gfx.is_none() {
        unusable = Some("no graphics+compute queue".to_string());
    } else if base.geometry_shader == 0 {
        // gl_PrimitiveID in the G-buffer fragment shader needs it.
        unusable = Some("geometryShader feature required (fragment gl_PrimitiveID)".to_string());
    } else {
        // Every Vulkan 1.2 feature create_device enables, except buffer device addresses: only acceleration
        // structures and the SBT need those, and RenderDoc 1.24 hides them on lavapipe (no
        // bufferDeviceAddressCaptureReplay), leaving the compute backend.
        let missing: Vec<&str> = [
            (v12.descriptor_indexing, "descriptorIndexing"),
            (v12.runtime_descriptor_array, "runtimeDescriptorArray"),
            (v12.descriptor_binding_partially_bound, "descriptorBindingPartiallyBound"),
            (v12.descriptor_binding_variable_descriptor_count, "descriptorBindingVariableDescriptorCount"),
            (
                v12.shader_sampled_image_array_non_uniform_indexing,
                "shaderSampledImageArrayNonUniformIndexing",
            ),
            (
                v12.shader_storage_buffer_array_non_uniform_indexing,
                "shaderStorageBufferArrayNonUniformIndexing",
            ),
            (v12.scalar_block_layout, "scalarBlockLayout"),
            (v12.host_query_reset, "hostQueryReset"),
        ]
        .into_iter()
        .filter(|(on, _)| *on == 0)
        .map(|(_, name)| name)
        .collect();
        if !missing.is_empty() {
            unusable = Some(format!("Vulkan 1.2 features required: {}", missing.join(", ")));
        }
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
        used_api_version,
        buffer_device_address: v12.buffer_device_address != 0,
        feature_path: feature_path.ok(),
        acceleration_structure: as_ok,
        ray_query: as_ok && has_rq && rqf.ray_query != 0,
        ray_tracing_pipeline: as_ok && has_rt && rtf.ray_tracing_pipeline != 0,
        trace_rays_indirect: as_ok && has_rt && rtf.ray_tracing_pipeline_trace_rays_indirect != 0,
        timestamp_period_ns: props.limits.timestamp_period,
        timestamps,
        subgroup_ops,
        subgroup_arithmetic,
        multi_draw_indirect: base.multi_draw_indirect != 0 && base.draw_indirect_first_instance != 0,
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

pub fn enumerate(
    instance: &ash::Instance,
    instance_api: u32,
) -> Result<Vec<(vk::PhysicalDevice, Capabilities)>> {
    let pds = unsafe { instance.enumerate_physical_devices() }.context("vkEnumeratePhysicalDevices")?;
    Ok(pds
        .into_iter()
        .enumerate()
        .map(|(i, pd)| (pd, query_capabilities(instance, pd, i, instance_api)))
        .collect())
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

    let path = caps.feature_path.as_ref().context("device has no usable feature path")?;
    exts.extend(path.extensions().iter().map(|e| e.as_ptr()));

    let base = vk::PhysicalDeviceFeatures::default()
        .geometry_shader(true)
        .multi_draw_indirect(caps.multi_draw_indirect)
        .draw_indirect_first_instance(caps.multi_draw_indirect);
    let mut v11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default()
        .buffer_device_address(caps.buffer_device_address)
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
    // The same features on a 1.2 device, one structure per extension.
    let mut sync2 = vk::PhysicalDeviceSynchronization2Features::default().synchronization2(true);
    let mut dynr = vk::PhysicalDeviceDynamicRenderingFeatures::default().dynamic_rendering(true);
    let mut eds = vk::PhysicalDeviceExtendedDynamicStateFeaturesEXT::default().extended_dynamic_state(true);
    let mut m4 = vk::PhysicalDeviceMaintenance4Features::default().maintenance4(true);
    let mut demote = vk::PhysicalDeviceShaderDemoteToHelperInvocationFeatures::default()
        .shader_demote_to_helper_invocation(true);
    let mut asf = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
    let mut rqf = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
    let mut rtf = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default()
        .ray_tracing_pipeline(true)
        .ray_tracing_pipeline_trace_rays_indirect(caps.trace_rays_indirect);

    let mut f2 =
        vk::PhysicalDeviceFeatures2::default().features(base).push_next(&mut v11).push_next(&mut v12);
    match path {
        FeaturePath::Core13 => f2 = f2.push_next(&mut v13),
        FeaturePath::Extensions12(_) => {
            f2 = f2.push_next(&mut sync2).push_next(&mut dynr).push_next(&mut eds);
            if path.has(khr::maintenance4::NAME) {
                f2 = f2.push_next(&mut m4);
            }
            if path.has(ext::shader_demote_to_helper_invocation::NAME) {
                f2 = f2.push_next(&mut demote);
            }
        }
    }
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
    let device = unsafe { instance.create_device(pd, &info, None) }.context("vkCreateDevice failed")?;
    // Reloaded so that on 1.2 the 1.3 entry points are the extensions' ones.
    Ok(features::load_device(instance, device.handle(), path))
}
