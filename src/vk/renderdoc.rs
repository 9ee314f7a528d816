//! RenderDoc's in-application API: `--capture-frame N` captures frame N itself (headless `render` /
//! `bench` have no window to press a capture key in). Found as `RENDERDOC_GetAPI` in `librenderdoc.so`:
//! already in the process under `renderdoccmd capture` (it preloads the library), else dlopen-ed. It
//! must be loaded before the Vulkan instance exists: loading makes RenderDoc enable its implicit Vulkan
//! layer (`VK_LAYER_RENDERDOC_Capture`), which records the API calls a capture needs.

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use ash::vk::{self, Handle as _};

/// `eRENDERDOC_API_Version_1_1_2`: the oldest layout with every function
/// used here (RenderDoc 1.24 offers up to 1.6.0, whose struct starts the same).
const API_VERSION_1_1_2: c_int = 10102;

type GetApiFn = unsafe extern "C" fn(version: c_int, out: *mut *mut c_void) -> c_int;

/// `RENDERDOC_API_1_1_2` up to `EndFrameCapture` (renderdoc_app.h); the
/// functions not called are kept as opaque pointers for the layout.
#[repr(C)]
struct Api {
    get_api_version: unsafe extern "C" fn(major: *mut c_int, minor: *mut c_int, patch: *mut c_int),
    _options_and_keys: [*const c_void; 8],
    _remove_hooks: *const c_void,
    _unload_crash_handler: *const c_void,
    set_capture_file_path_template: unsafe extern "C" fn(template: *const c_char),
    get_capture_file_path_template: unsafe extern "C" fn() -> *const c_char,
    get_num_captures: unsafe extern "C" fn() -> u32,
    get_capture: unsafe extern "C" fn(
        idx: u32,
        filename: *mut c_char,
        pathlength: *mut u32,
        timestamp: *mut u64,
    ) -> u32,
    _trigger_capture: *const c_void,
    _is_target_control_connected: *const c_void,
    _launch_replay_ui: *const c_void,
    _set_active_window: *const c_void,
    start_frame_capture: unsafe extern "C" fn(device: *const c_void, window: *const c_void),
    is_frame_capturing: unsafe extern "C" fn() -> u32,
    end_frame_capture: unsafe extern "C" fn(device: *const c_void, window: *const c_void) -> u32,
}

/// The library name RenderDoc installs (Debian: package librenderdoc, a
/// dependency of renderdoccmd); `HYBRID_RT_RENDERDOC_LIB` overrides it.
const LIBRARY: &str = "librenderdoc.so";

/// A loaded RenderDoc in-application API.
pub struct RenderDoc {
    api: *const Api,
    /// Whether the library was in the process already (renderdoccmd).
    pub preloaded: bool,
    pub version: (i32, i32, i32),
    /// Keeps the library mapped while `api` is used.
    _lib: libloading::os::unix::Library,
}

// SAFETY: RenderDoc's API functions may be called from any thread; the
// struct they live in is static in the library, which `_lib` keeps loaded.
unsafe impl Send for RenderDoc {}
unsafe impl Sync for RenderDoc {}

impl RenderDoc {
    /// The API of the RenderDoc this process runs under, if any (the library is not loaded otherwise).
    pub fn running() -> Option<Result<RenderDoc>> {
        let this = libloading::os::unix::Library::this();
        unsafe { this.get::<GetApiFn>(b"RENDERDOC_GetAPI\0") }.is_ok().then(RenderDoc::load)
    }

    /// The API of the RenderDoc this process runs under, or of a loadable
    /// `librenderdoc.so`; an error says how to get one.
    pub fn load() -> Result<RenderDoc> {
        use libloading::os::unix::{Library, RTLD_NOW};
        // Under renderdoccmd the library is preloaded into the global scope.
        let this = Library::this();
        let preloaded = unsafe { this.get::<GetApiFn>(b"RENDERDOC_GetAPI\0") }.is_ok();
        let name = std::env::var("HYBRID_RT_RENDERDOC_LIB").unwrap_or_else(|_| LIBRARY.to_string());
        // SAFETY: loading RenderDoc runs its initialisation, which only
        // installs its hooks; dlopen of a loaded library returns it again.
        let lib = match unsafe { Library::open(Some(&name), RTLD_NOW) } {
            Ok(lib) => lib,
            Err(e) => bail!(
                "--capture-frame needs RenderDoc: run under `renderdoccmd capture ...`, or install it so that \
                 {name} can be loaded (Debian: apt-get install renderdoccmd); loading it failed: {e}"
            ),
        };
        let get_api = unsafe { lib.get::<GetApiFn>(b"RENDERDOC_GetAPI\0") }
            .with_context(|| format!("{name} has no RENDERDOC_GetAPI: not RenderDoc's capture library?"))?;
        let mut api: *mut c_void = std::ptr::null_mut();
        // SAFETY: the documented entry point; it fills `api` on success.
        if unsafe { get_api(API_VERSION_1_1_2, &mut api) } != 1 || api.is_null() {
            bail!("{name}: RENDERDOC_GetAPI refused API version 1.1.2 (RenderDoc older than 1.1?)");
        }
        let api = api as *const Api;
        let mut version = (0, 0, 0);
        unsafe { ((*api).get_api_version)(&mut version.0, &mut version.1, &mut version.2) };
        let rd = RenderDoc { api, preloaded, version, _lib: lib };
        log::info!(
            "renderdoc: in-application API {}.{}.{} ({}), captures go to {}*",
            version.0,
            version.1,
            version.2,
            if preloaded { "running under RenderDoc" } else { "loaded librenderdoc.so" },
            rd.path_template()
        );
        Ok(rd)
    }

    fn api(&self) -> &Api {
        // SAFETY: returned by RENDERDOC_GetAPI, static while `_lib` lives.
        unsafe { &*self.api }
    }

    /// Where captures are written: the template plus `_frameN.rdc`.
    pub fn path_template(&self) -> String {
        let p = unsafe { (self.api().get_capture_file_path_template)() };
        if p.is_null() {
            return String::new();
        }
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }

    /// Sets the capture path template (RenderDoc appends `_frameN.rdc`).
    pub fn set_path_template(&self, template: &str) -> Result<()> {
        let c = CString::new(template).context("capture path with a NUL byte")?;
        unsafe { (self.api().set_capture_file_path_template)(c.as_ptr()) };
        Ok(())
    }

    /// The device pointer RenderDoc wants for Vulkan: the dispatch table
    /// pointer at the start of the VkInstance (RENDERDOC_DEVICEPOINTER_FROM_VKINSTANCE).
    fn device_pointer(instance: vk::Instance) -> *const c_void {
        // SAFETY: a dispatchable handle points at its dispatch table pointer.
        unsafe { *(instance.as_raw() as *const *const c_void) }
    }

    /// Starts capturing everything submitted on `instance`'s devices.
    pub fn start(&self, instance: vk::Instance) {
        unsafe { (self.api().start_frame_capture)(Self::device_pointer(instance), std::ptr::null()) };
    }

    pub fn is_capturing(&self) -> bool {
        unsafe { (self.api().is_frame_capturing)() != 0 }
    }

    /// Ends the capture started by [`RenderDoc::start`]; returns the file it was written to.
    pub fn end(&self, instance: vk::Instance) -> Result<PathBuf> {
        let ok = unsafe { (self.api().end_frame_capture)(Self::device_pointer(instance), std::ptr::null()) };
        if ok != 1 {
            bail!(
                "RenderDoc failed to write the capture (EndFrameCapture returned {ok}); see RenderDoc's log"
            );
        }
        let n = unsafe { (self.api().get_num_captures)() };
        self.capture_path(n.checked_sub(1).context("RenderDoc reports no capture after EndFrameCapture")?)
    }

    fn capture_path(&self, idx: u32) -> Result<PathBuf> {
        let mut len = 0u32;
        let get = self.api().get_capture;
        if unsafe { get(idx, std::ptr::null_mut(), &mut len, std::ptr::null_mut()) } != 1 {
            bail!("RenderDoc has no capture {idx}");
        }
        let mut buf = vec![0u8; len as usize + 1];
        unsafe { get(idx, buf.as_mut_ptr() as *mut c_char, &mut len, std::ptr::null_mut()) };
        let s = CStr::from_bytes_until_nul(&buf).context("capture path without NUL")?;
        Ok(PathBuf::from(s.to_string_lossy().into_owned()))
    }
}
