//! How the renderer reaches the Vulkan 1.3 features it uses: as core 1.3, or on a 1.2 device through the
//! extensions 1.3 promoted. RenderDoc 1.24 (Debian 12's package) shows lavapipe as a 1.2 device; without
//! this path the one profiler packaged for the CI platform could not capture a frame. Call sites are the
//! same on both paths: the 1.3 entry points are loaded under their extension names ([`load_device`]).

use std::ffi::{c_void, CStr, CString};

use ash::{ext, khr, vk};

/// Extensions a Vulkan 1.2 device must offer, with what needs them.
pub const REQUIRED_1_2: &[(&CStr, &str)] = &[
    (khr::synchronization2::NAME, "barriers, submits and timestamps (render/frame.rs, vk/timer.rs)"),
    (khr::dynamic_rendering::NAME, "the G-buffer pass (render/passes/gbuffer.rs)"),
    (ext::extended_dynamic_state::NAME, "the per-draw cull mode of the G-buffer pass"),
];

/// Enabled on a 1.2 device when offered, as the 1.3 path enables them; nothing relies on them (SPIR-V
/// 1.5 has no demote unless a shader asks, and no maintenance4 entry point is called), so a 1.2 device
/// without them is still usable.
pub const OPTIONAL_1_2: &[&CStr] = &[khr::maintenance4::NAME, ext::shader_demote_to_helper_invocation::NAME];

/// The 1.3 entry points each extension provides under its own suffix.
const PROMOTED: &[(&CStr, &str, &[&str])] = &[
    (
        khr::synchronization2::NAME,
        "KHR",
        &[
            "vkCmdSetEvent2",
            "vkCmdResetEvent2",
            "vkCmdWaitEvents2",
            "vkCmdPipelineBarrier2",
            "vkCmdWriteTimestamp2",
            "vkQueueSubmit2",
        ],
    ),
    (khr::dynamic_rendering::NAME, "KHR", &["vkCmdBeginRendering", "vkCmdEndRendering"]),
    (
        ext::extended_dynamic_state::NAME,
        "EXT",
        &[
            "vkCmdSetCullMode",
            "vkCmdSetFrontFace",
            "vkCmdSetPrimitiveTopology",
            "vkCmdSetViewportWithCount",
            "vkCmdSetScissorWithCount",
            "vkCmdBindVertexBuffers2",
            "vkCmdSetDepthTestEnable",
            "vkCmdSetDepthWriteEnable",
            "vkCmdSetDepthCompareOp",
            "vkCmdSetDepthBoundsTestEnable",
            "vkCmdSetStencilTestEnable",
            "vkCmdSetStencilOp",
        ],
    ),
    (
        khr::maintenance4::NAME,
        "KHR",
        &[
            "vkGetDeviceBufferMemoryRequirements",
            "vkGetDeviceImageMemoryRequirements",
            "vkGetDeviceImageSparseMemoryRequirements",
        ],
    ),
];

/// How the 1.3 features are reached on a device.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FeaturePath {
    /// A Vulkan 1.3 device: core features and entry points.
    Core13,
    /// A Vulkan 1.2 device: these extensions enabled (required ones first).
    Extensions12(Vec<&'static CStr>),
}

impl FeaturePath {
    /// "Vulkan 1.3 core" or "Vulkan 1.2 + extensions VK_KHR_synchronization2, ...".
    pub fn describe(&self) -> String {
        match self {
            FeaturePath::Core13 => "Vulkan 1.3 core".to_string(),
            FeaturePath::Extensions12(exts) => {
                let names: Vec<_> = exts.iter().map(|e| e.to_string_lossy()).collect();
                format!("Vulkan 1.2 + extensions {}", names.join(", "))
            }
        }
    }

    /// The extensions to enable on the device (none on 1.3).
    pub fn extensions(&self) -> &[&'static CStr] {
        match self {
            FeaturePath::Core13 => &[],
            FeaturePath::Extensions12(exts) => exts,
        }
    }

    pub fn has(&self, name: &CStr) -> bool {
        self.extensions().contains(&name)
    }
}

fn has_ext(exts: &[vk::ExtensionProperties], name: &CStr) -> bool {
    exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name))
}

/// The path for device `pd` used at API version `api` (the lower of the
/// instance's and the device's), or why the device is unusable.
pub fn choose(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    api: u32,
    exts: &[vk::ExtensionProperties],
) -> Result<FeaturePath, String> {
    if api >= vk::API_VERSION_1_3 {
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v13);
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
        if v13.dynamic_rendering == 0 || v13.synchronization2 == 0 {
            return Err("dynamic rendering and synchronization2 required".to_string());
        }
        return Ok(FeaturePath::Core13);
    }
    if api < vk::API_VERSION_1_2 {
        return Err("Vulkan 1.2 required (1.3, or 1.2 with the extensions 1.3 promoted)".to_string());
    }
    let missing: Vec<String> = REQUIRED_1_2
        .iter()
        .filter(|(name, _)| !has_ext(exts, name))
        .map(|(name, why)| format!("{} ({why})", name.to_string_lossy()))
        .collect();
    if !missing.is_empty() {
        return Err(format!("Vulkan 1.2 device without {}", missing.join(", ")));
    }
    // Only structures of offered extensions go into the chain.
    let mut sync2 = vk::PhysicalDeviceSynchronization2Features::default();
    let mut dynr = vk::PhysicalDeviceDynamicRenderingFeatures::default();
    let mut eds = vk::PhysicalDeviceExtendedDynamicStateFeaturesEXT::default();
    let mut m4 = vk::PhysicalDeviceMaintenance4Features::default();
    let mut demote = vk::PhysicalDeviceShaderDemoteToHelperInvocationFeatures::default();
    let (has_m4, has_demote) = (
        has_ext(exts, khr::maintenance4::NAME),
        has_ext(exts, ext::shader_demote_to_helper_invocation::NAME),
    );
    {
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut sync2)
            .push_next(&mut dynr)
            .push_next(&mut eds);
        if has_m4 {
            f2 = f2.push_next(&mut m4);
        }
        if has_demote {
            f2 = f2.push_next(&mut demote);
        }
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    }
    let off: Vec<&str> = [
        (sync2.synchronization2, "synchronization2"),
        (dynr.dynamic_rendering, "dynamicRendering"),
        (eds.extended_dynamic_state, "extendedDynamicState"),
    ]
    .into_iter()
    .filter(|(on, _)| *on == 0)
    .map(|(_, name)| name)
    .collect();
    if !off.is_empty() {
        return Err(format!("Vulkan 1.2 device: extension offered but feature off: {}", off.join(", ")));
    }
    let mut enabled: Vec<&'static CStr> = REQUIRED_1_2.iter().map(|(n, _)| *n).collect();
    if has_m4 && m4.maintenance4 != 0 {
        enabled.push(khr::maintenance4::NAME);
    }
    if has_demote && demote.shader_demote_to_helper_invocation != 0 {
        enabled.push(ext::shader_demote_to_helper_invocation::NAME);
    }
    Ok(FeaturePath::Extensions12(enabled))
}

/// The name 1.3 entry point `name` has on the 1.2 path, if an enabled extension provides it.
fn alias(name: &CStr, path: &FeaturePath) -> Option<CString> {
    let s = name.to_str().ok()?;
    let (ext, suffix, _) = PROMOTED.iter().find(|(_, _, fns)| fns.contains(&s))?;
    path.has(ext).then(|| CString::new(format!("{s}{suffix}")).expect("no NUL in an entry point name"))
}

/// Loads the device's entry points. On the 1.2 path the 1.3 ones come from their extensions
/// (`vkCmdPipelineBarrier2KHR` behind `cmd_pipeline_barrier2`, ...); a 1.3 entry point no enabled
/// extension provides stays unloaded (ash panics if called) rather than call 1.3 on a 1.2 device.
pub fn load_device(instance: &ash::Instance, device: vk::Device, path: &FeaturePath) -> ash::Device {
    let gdpa = instance.fp_v1_0().get_device_proc_addr;
    // SAFETY: a valid device and a NUL-terminated name.
    let get = |n: &CStr| unsafe { gdpa(device, n.as_ptr()) }.map_or(std::ptr::null(), |f| f as *const c_void);
    let mut core = |name: &CStr| get(name);
    let mut v13 = |name: &CStr| match path {
        FeaturePath::Core13 => get(name),
        FeaturePath::Extensions12(_) => alias(name, path).map_or(std::ptr::null(), |n| get(&n)),
    };
    ash::Device::from_parts_1_3(
        device,
        ash::DeviceFnV1_0::load(&mut core),
        ash::DeviceFnV1_1::load(&mut core),
        ash::DeviceFnV1_2::load(&mut core),
        ash::DeviceFnV1_3::load(&mut v13),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aliases_follow_the_enabled_extensions() {
        let path =
            FeaturePath::Extensions12(vec![khr::synchronization2::NAME, ext::extended_dynamic_state::NAME]);
        assert_eq!(alias(c"vkCmdPipelineBarrier2", &path), Some(c"vkCmdPipelineBarrier2KHR".into()));
        assert_eq!(alias(c"vkCmdSetCullMode", &path), Some(c"vkCmdSetCullModeEXT".into()));
        // Dynamic rendering not enabled, and a 1.3 entry point no extension here provides: neither is loaded.
        assert_eq!(alias(c"vkCmdBeginRendering", &path), None);
        assert_eq!(alias(c"vkCmdCopyBuffer2", &path), None);
        assert_eq!(
            path.describe(),
            "Vulkan 1.2 + extensions VK_KHR_synchronization2, VK_EXT_extended_dynamic_state"
        );
        assert_eq!(FeaturePath::Core13.describe(), "Vulkan 1.3 core");
    }
}
