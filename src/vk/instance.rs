//! Vulkan instance, the optional Khronos validation layer and the debug-utils
//! messenger that routes its messages to `log` and counts errors.

use std::ffi::{c_void, CStr, CString};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

use anyhow::{bail, Context as _, Result};
use ash::{ext, vk};

pub const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Counts of validation messages by severity; tests assert these stay zero. The `Arc` outlives the
/// instance: read them after the context is dropped to include teardown (leaked objects).
#[derive(Debug, Default)]
pub struct ValidationCounters {
    pub errors: AtomicU32,
    pub warnings: AtomicU32,
}

impl ValidationCounters {
    pub fn errors(&self) -> u32 {
        self.errors.load(Ordering::Relaxed)
    }
    pub fn warnings(&self) -> u32 {
        self.warnings.load(Ordering::Relaxed)
    }
}

#[derive(Clone, Debug, Default)]
pub struct InstanceOptions {
    pub validation: bool,
    /// Also enable synchronization validation (slower).
    pub sync_validation: bool,
    /// Surface extensions a window needs (from ash-window), empty when headless.
    pub surface_extensions: Vec<*const std::ffi::c_char>,
    /// Ask for at most this Vulkan API version (`--vulkan-api 1.2`): the device is then used as 1.2, which
    /// tests the extension path RenderDoc 1.24 needs without RenderDoc.
    pub max_api_version: Option<u32>,
}

pub struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    pub debug_utils: Option<ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    pub counters: Arc<ValidationCounters>,
    pub validation: bool,
    /// The API version the instance was created with: a device is used at
    /// the lower of this and its own version.
    pub api_version: u32,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    ty: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    let counters = &*(user as *const ValidationCounters);
    let msg = if data.is_null() || (*data).p_message.is_null() {
        std::borrow::Cow::Borrowed("(no message)")
    } else {
        CStr::from_ptr((*data).p_message).to_string_lossy()
    };
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        counters.errors.fetch_add(1, Ordering::Relaxed);
        log::error!(target: "vulkan", "[{ty:?}] {msg}");
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        counters.warnings.fetch_add(1, Ordering::Relaxed);
        log::warn!(target: "vulkan", "[{ty:?}] {msg}");
    } else {
        log::debug!(target: "vulkan", "[{ty:?}] {msg}");
    }
    vk::FALSE
}

impl Instance {
    pub fn new(opts: &InstanceOptions) -> Result<Instance> {
        // SAFETY: loads the system Vulkan loader; failure is reported, not UB.
        let entry = unsafe { ash::Entry::load() }
            .context("cannot load the Vulkan loader (libvulkan.so.1); install libvulkan1 and a driver")?;
        let loader = unsafe { entry.try_enumerate_instance_version()? }.unwrap_or(vk::API_VERSION_1_0);
        // 1.2 is enough: the 1.3 features the renderer uses are also
        // extensions of 1.2 (see device.rs, FeaturePath).
        if loader < vk::API_VERSION_1_2 {
            bail!(
                "the Vulkan loader supports API {}.{}, this renderer needs 1.2 (1.3 preferred)",
                vk::api_version_major(loader),
                vk::api_version_minor(loader)
            );
        }
        let api = [Some(vk::API_VERSION_1_3), Some(loader), opts.max_api_version]
            .into_iter()
            .flatten()
            .min()
            .unwrap_or(vk::API_VERSION_1_3);
        if api < vk::API_VERSION_1_2 {
            bail!("a Vulkan API version below 1.2 was asked for; the renderer needs 1.2");
        }

        let layers = unsafe { entry.enumerate_instance_layer_properties()? };
        let has_layer = |name: &CStr| layers.iter().any(|l| l.layer_name_as_c_str() == Ok(name));
        let mut exts = unsafe { entry.enumerate_instance_extension_properties(None)? };
        let mut layer_names = Vec::new();
        if opts.validation {
            if !has_layer(VALIDATION_LAYER) {
                bail!("validation requested but VK_LAYER_KHRONOS_validation is not installed (Debian: vulkan-validationlayers)");
            }
            layer_names.push(VALIDATION_LAYER.as_ptr());
            // The layer itself may be what provides debug utils.
            exts.extend(unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION_LAYER)) }?);
        }
        let has_debug_utils = exts.iter().any(|e| e.extension_name_as_c_str() == Ok(ext::debug_utils::NAME));
        if opts.validation && !has_debug_utils {
            // Without a messenger nothing would be counted: the run would
            // look clean whatever the layer found.
            bail!("validation requested but VK_EXT_debug_utils is unavailable, so validation messages cannot be counted");
        }
        let mut ext_names = opts.surface_extensions.clone();
        if has_debug_utils {
            ext_names.push(ext::debug_utils::NAME.as_ptr());
        }

        let app_name = CString::new("hybrid-rt").unwrap();
        let app = vk::ApplicationInfo::default()
            .application_name(&app_name)
            .application_version(1)
            .engine_name(&app_name)
            .api_version(api);

        let counters = Arc::new(ValidationCounters::default());
        let severity = vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
            | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
            | vk::DebugUtilsMessageSeverityFlagsEXT::INFO;
        let types = vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
            | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
            | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE;
        let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(severity)
            .message_type(types)
            .pfn_user_callback(Some(debug_callback))
            .user_data(Arc::as_ptr(&counters) as *mut c_void);

        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&ext_names);
        if opts.validation && has_debug_utils {
            // Also catches messages from vkCreateInstance / vkDestroyInstance.
            info = info.push_next(&mut messenger_info);
        }
        if opts.validation && opts.sync_validation {
            info = info.push_next(&mut features);
        }
        let raw = unsafe { entry.create_instance(&info, None) }.context("vkCreateInstance failed")?;
        if opts.validation {
            log::info!(
                "VK_LAYER_KHRONOS_validation is on (synchronization validation: {})",
                opts.sync_validation
            );
        }

        let debug_utils = has_debug_utils.then(|| ext::debug_utils::Instance::new(&entry, &raw));
        // Lives until Drop so teardown's messages (objects leaked at vkDestroyDevice) are counted too;
        // vkDestroyInstance's go to the create-info messenger chained above.
        let messenger = match (&debug_utils, opts.validation) {
            (Some(du), true) => {
                let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                    .message_severity(severity)
                    .message_type(types)
                    .pfn_user_callback(Some(debug_callback))
                    .user_data(Arc::as_ptr(&counters) as *mut c_void);
                unsafe { du.create_debug_utils_messenger(&info, None)? }
            }
            _ => vk::DebugUtilsMessengerEXT::null(),
        };
        Ok(Instance {
            entry,
            raw,
            debug_utils,
            messenger,
            counters,
            validation: opts.validation,
            api_version: api,
        })
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        unsafe {
            if let Some(du) = &self.debug_utils {
                if self.messenger != vk::DebugUtilsMessengerEXT::null() {
                    du.destroy_debug_utils_messenger(self.messenger, None);
                }
            }
            self.raw.destroy_instance(None);
        }
    }
}
