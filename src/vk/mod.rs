//! Vulkan core: instance, device, memory, commands, debug names and labels,
//! timestamp queries, shader modules.

mod built;
pub mod device;
pub mod features;
pub mod frame_ring;
pub mod instance;
pub mod limits;
pub mod memory;
pub mod pipeline;
pub mod raster;
pub mod reflect;
pub mod renderdoc;
pub mod rt_pipeline;
pub mod timer;

use std::ffi::CString;
use std::mem::ManuallyDrop;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use anyhow::{Context as _, Result};
use ash::{ext, khr, vk};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

pub use built::{built, Destroy};
pub use device::{Capabilities, DeviceSelector, RtEnables};
pub use features::FeaturePath;
pub use instance::{Instance, InstanceOptions, ValidationCounters};
pub use memory::{Buffer, Image, STAGING_BYTES};
pub use renderdoc::RenderDoc;

/// How to create the Vulkan context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Which device, validation, and the features left off.
    pub gpu: GpuOptions,
    pub surface_extensions: Vec<*const std::ffi::c_char>,
    pub swapchain: bool,
    /// RenderDoc's in-application API: load it (before the instance).
    pub renderdoc: RenderDocUse,
}

/// The device options every command that touches the GPU takes (the command line's `GpuArgs` make them once).
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    pub validation: bool,
    pub sync_validation: bool,
    pub device: DeviceSelector,
    pub disable_ray_tracing: bool,
    /// `--no-ray-query`: ray tracing without VK_KHR_ray_query.
    pub disable_ray_query: bool,
    /// No indirect ray-tracing launch even where the device has one (tests).
    pub disable_trace_rays_indirect: bool,
    /// No subgroup arithmetic even where the device has it (tests of the portable paths).
    pub disable_subgroup_arithmetic: bool,
    /// `--vulkan-api 1.2`: use the device as a Vulkan 1.2 device.
    pub max_api_version: Option<u32>,
    /// `--capture-frame N` (render, bench, view): capture frame N with RenderDoc's in-application API.
    pub capture_frame: Option<u64>,
}

/// Whether a context loads RenderDoc's in-application API.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RenderDocUse {
    #[default]
    Off,
    /// When the process runs under RenderDoc (the viewer's capture key).
    IfRunning,
    /// Load it or fail (`--capture-frame`).
    Required,
}

/// Everything a pass needs to talk to the GPU.
pub struct Context {
    pub instance: Instance,
    pub physical_device: vk::PhysicalDevice,
    pub caps: Capabilities,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub command_pool: vk::CommandPool,
    /// Command buffers `one_shot` finished with, reused rather than freed: with Khronos validation
    /// 1.3.239 (Debian 12's), freeing a labelled command buffer per submission corrupted the heap when
    /// two contexts ran at once (the tests): the layer erases a freed command buffer's debug-label state
    /// without its lock (Vulkan-ValidationLayers issue 5172, fixed after 1.3.239).
    one_shot_spare: Mutex<Vec<vk::CommandBuffer>>,
    pub debug_utils: Option<ext::debug_utils::Device>,
    pub rt: RtEnables,
    pub accel: Option<khr::acceleration_structure::Device>,
    pub rt_pipeline: Option<khr::ray_tracing_pipeline::Device>,
    /// Synchronization validation is on: nothing may hide a missing barrier.
    pub sync_validation: bool,
    /// Fault injection for tests of error paths (off unless armed).
    pub alloc_fault: AllocationFault,
    /// RenderDoc's in-application API, when loaded.
    pub renderdoc: Option<renderdoc::RenderDoc>,
    /// The frame `--capture-frame` asked for.
    pub capture_frame: Option<u64>,
}

/// Makes the n-th buffer or image allocation from now fail as running out of device memory would: tests
/// walk every failure point of a code path and check, under validation, that each error leaks nothing.
#[derive(Default)]
pub struct AllocationFault(std::sync::atomic::AtomicU64);

impl AllocationFault {
    /// Fail the `n`-th allocation from now (n >= 1); 0 disarms.
    pub fn arm(&self, n: u64) {
        self.0.store(n, std::sync::atomic::Ordering::SeqCst);
    }

    /// Counts one allocation; true when it is the one to fail.
    pub(crate) fn hit(&self) -> bool {
        use std::sync::atomic::Ordering::SeqCst;
        self.0.fetch_update(SeqCst, SeqCst, |n| (n > 0).then(|| n - 1)) == Ok(1)
    }
}

impl Context {
    pub fn new(opts: &ContextOptions) -> Result<Context> {
        // Before the instance: loading RenderDoc enables its Vulkan layer.
        let renderdoc = match opts.renderdoc {
            RenderDocUse::Off => None,
            RenderDocUse::IfRunning => renderdoc::RenderDoc::running().transpose()?,
            RenderDocUse::Required => Some(renderdoc::RenderDoc::load()?),
        };
        let instance = Instance::new(&InstanceOptions {
            validation: opts.gpu.validation,
            sync_validation: opts.gpu.sync_validation,
            surface_extensions: opts.surface_extensions.clone(),
            max_api_version: opts.gpu.max_api_version,
        })?;
        let devices = device::enumerate(&instance.raw, instance.api_version)?;
        for (_, c) in &devices {
            log::debug!("found {}", c.report().trim_end());
        }
        let (pd, mut caps) = device::select(&devices, &opts.gpu.device)?;
        caps.trace_rays_indirect &= !opts.gpu.disable_trace_rays_indirect;
        caps.subgroup_arithmetic &= !opts.gpu.disable_subgroup_arithmetic;
        let rt = if opts.gpu.disable_ray_tracing {
            RtEnables::default()
        } else {
            RtEnables {
                acceleration_structure: caps.acceleration_structure,
                ray_query: caps.ray_query && !opts.gpu.disable_ray_query,
                ray_tracing_pipeline: caps.ray_tracing_pipeline,
            }
        };
        log::info!(
            "using {} ({}, {} {}), Vulkan {} ({}); ray-tracing extensions enabled: AS {} / query {} / pipeline {}",
            caps.name,
            match caps.device_type {
                vk::PhysicalDeviceType::CPU => "software",
                vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
                vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
                _ => "other",
            },
            caps.driver_name,
            caps.driver_info,
            caps.api_used_string(),
            caps.feature_path_string(),
            rt.acceleration_structure,
            rt.ray_query,
            rt.ray_tracing_pipeline
        );
        let device = device::create_device(&instance.raw, pd, &caps, rt, opts.swapchain)?;
        let queue = unsafe { device.get_device_queue(caps.graphics_queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: device.clone(),
            physical_device: pd,
            debug_settings: Default::default(),
            // Memory for device addresses only where the feature is on.
            buffer_device_address: caps.buffer_device_address,
            allocation_sizes: Default::default(),
        })
        .context("creating the GPU memory allocator")?;
        let command_pool = unsafe {
            device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(caps.graphics_queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )?
        };
        let debug_utils =
            instance.debug_utils.as_ref().map(|_| ext::debug_utils::Device::new(&instance.raw, &device));
        let accel = rt
            .acceleration_structure
            .then(|| khr::acceleration_structure::Device::new(&instance.raw, &device));
        let rt_pipeline = rt.ray_tracing_pipeline.then(|| rt_pipeline::loader(&instance.raw, &device));
        let ctx = Context {
            queue_family: caps.graphics_queue_family,
            instance,
            physical_device: pd,
            caps,
            device,
            queue,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            command_pool,
            one_shot_spare: Mutex::new(Vec::new()),
            debug_utils,
            rt,
            accel,
            rt_pipeline,
            sync_validation: opts.gpu.validation && opts.gpu.sync_validation,
            alloc_fault: AllocationFault::default(),
            renderdoc,
            capture_frame: opts.gpu.capture_frame,
        };
        ctx.name(ctx.queue, "main queue");
        ctx.name(ctx.command_pool, "main command pool");
        Ok(ctx)
    }

    /// The validation counters; they outlive the context, and only a read
    /// after it is dropped includes teardown (see [`Context::finish`]).
    pub fn validation_counters(&self) -> Arc<ValidationCounters> {
        self.instance.counters.clone()
    }

    /// Destroys the context, then fails if the validation layer reported any error during its life or
    /// teardown (objects leaked at vkDestroyDevice / vkDestroyInstance).
    pub fn finish(self) -> Result<()> {
        let counters = self.validation_counters();
        drop(self);
        match counters.errors() {
            0 => Ok(()),
            n => anyhow::bail!(
                "the Vulkan validation layer reported {n} error(s), teardown included; see the log above"
            ),
        }
    }

    /// Gives a Vulkan object a debug name (shown by validation, RenderDoc, Nsight).
    pub fn name<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(du) = &self.debug_utils else { return };
        let Ok(c) = CString::new(name) else { return };
        let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&c);
        unsafe {
            let _ = du.set_debug_utils_object_name(&info);
        }
    }

    /// Opens a named region in a command buffer (a pass label).
    pub fn begin_label(&self, cmd: vk::CommandBuffer, name: &str, color: [f32; 4]) {
        let Some(du) = &self.debug_utils else { return };
        let Ok(c) = CString::new(name) else { return };
        let label = vk::DebugUtilsLabelEXT::default().label_name(&c).color(color);
        unsafe { du.cmd_begin_debug_utils_label(cmd, &label) };
    }

    pub fn end_label(&self, cmd: vk::CommandBuffer) {
        if let Some(du) = &self.debug_utils {
            unsafe { du.cmd_end_debug_utils_label(cmd) };
        }
    }

    pub fn allocate_command_buffer(&self, name: &str) -> Result<vk::CommandBuffer> {
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = unsafe { self.device.allocate_command_buffers(&info)? }[0];
        self.name(cmd, name);
        Ok(cmd)
    }

    /// Resets `cmd` and begins recording it for one submission.
    pub fn begin_commands(&self, cmd: vk::CommandBuffer) -> Result<()> {
        unsafe {
            self.device.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())?;
            self.device.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
        }
        Ok(())
    }

    /// Records `f` into a command buffer of its own (a spare one reused, see `one_shot_spare`), submits
    /// it and waits.
    pub fn one_shot<R>(&self, name: &str, f: impl FnOnce(vk::CommandBuffer) -> Result<R>) -> Result<R> {
        let cmd = self.begin_spare(name)?;
        let r = match f(cmd) {
            Ok(r) => r,
            Err(e) => {
                self.drop_spare(cmd);
                return Err(e);
            }
        };
        self.submit_spare(cmd)?;
        Ok(r)
    }

    /// A command buffer of its own, begun and labelled `name`, for `submit_spare` (a spare one reused,
    /// see `one_shot_spare`).
    pub fn begin_spare(&self, name: &str) -> Result<vk::CommandBuffer> {
        let spare = self.one_shot_spare.lock().unwrap().pop();
        let cmd = match spare {
            Some(cmd) => {
                self.name(cmd, name);
                cmd
            }
            None => self.allocate_command_buffer(name)?,
        };
        if let Err(e) = self.begin_commands(cmd) {
            self.drop_spare(cmd);
            return Err(e);
        }
        self.begin_label(cmd, name, [0.6, 0.6, 0.6, 1.0]);
        Ok(cmd)
    }

    /// Ends, submits and waits for a command buffer from `begin_spare`; it becomes a spare again.
    pub fn submit_spare(&self, cmd: vk::CommandBuffer) -> Result<()> {
        self.end_label(cmd);
        let r = unsafe { self.device.end_command_buffer(cmd) }
            .map_err(anyhow::Error::from)
            .and_then(|_| self.submit_and_wait(cmd));
        match r {
            Ok(()) => self.one_shot_spare.lock().unwrap().push(cmd),
            Err(_) => self.drop_spare(cmd),
        }
        r
    }

    /// Frees a command buffer from `begin_spare` that failed: it may still be pending (a failed wait), so
    /// it is never reused.
    pub fn drop_spare(&self, cmd: vk::CommandBuffer) {
        unsafe { self.device.free_command_buffers(self.command_pool, &[cmd]) };
    }

    pub fn submit_and_wait(&self, cmd: vk::CommandBuffer) -> Result<()> {
        let fence = unsafe { self.device.create_fence(&vk::FenceCreateInfo::default(), None)? };
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = vk::SubmitInfo2::default().command_buffer_infos(&cmds);
        let r = unsafe {
            self.device
                .queue_submit2(self.queue, &[submit], fence)
                .and_then(|_| self.device.wait_for_fences(&[fence], true, u64::MAX))
        };
        unsafe { self.device.destroy_fence(fence, None) };
        r.context("queue submit / wait (device lost?)")
    }

    /// Whether `frame` is the frame `--capture-frame` asked for.
    pub fn wants_capture(&self, frame: u64) -> bool {
        self.capture_frame == Some(frame)
    }

    /// Starts a RenderDoc capture of everything submitted until
    /// [`Context::end_capture`]; `what` names it in the log.
    pub fn start_capture(&self, what: &str) -> Result<()> {
        let rd = self.renderdoc.as_ref().context(
            "RenderDoc is not loaded: run under `renderdoccmd capture ...` or pass --capture-frame N",
        )?;
        rd.start(self.instance.raw.handle());
        anyhow::ensure!(rd.is_capturing(), "RenderDoc did not start capturing {what}");
        log::info!("renderdoc: capturing {what}");
        Ok(())
    }

    /// Ends the capture; logs and returns the capture file.
    pub fn end_capture(&self, what: &str) -> Result<PathBuf> {
        let rd = self.renderdoc.as_ref().context("RenderDoc is not loaded")?;
        let path = rd.end(self.instance.raw.handle())?;
        log::info!("renderdoc: captured {what} to {}", path.display());
        Ok(path)
    }

    /// Runs `f` inside a capture when `frame` is the one asked for; the capture is ended on `f`'s error too.
    pub fn capture_frame_if<R>(&self, frame: u64, what: &str, f: impl FnOnce() -> Result<R>) -> Result<R> {
        if !self.wants_capture(frame) {
            return f();
        }
        self.start_capture(what)?;
        let r = f();
        let ended = self.end_capture(what);
        let r = r?;
        ended?;
        Ok(r)
    }

    /// Bytes of device memory currently allocated through gpu-allocator.
    pub fn allocated_bytes(&self) -> u64 {
        let a = self.allocator.lock().unwrap();
        a.generate_report().total_allocated_bytes
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_command_pool(self.command_pool, None);
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
        }
    }
}

/// A full pipeline barrier for one image layout transition (sync2).
#[allow(clippy::too_many_arguments)]
pub fn image_barrier(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let b = [vk::ImageMemoryBarrier2::default()
        .image(image)
        .old_layout(old)
        .new_layout(new)
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(aspect)
                .level_count(vk::REMAINING_MIP_LEVELS)
                .layer_count(vk::REMAINING_ARRAY_LAYERS),
        )];
    unsafe {
        ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&b))
    };
}

/// Records the copy of a whole single-mip image, in TRANSFER_SRC_OPTIMAL,
/// into `buffer` (tightly packed rows): every readback goes through here.
pub fn copy_image_to_buffer(ctx: &Context, cmd: vk::CommandBuffer, image: &Image, buffer: vk::Buffer) {
    let region = [vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(image.aspect).layer_count(1))
        .image_extent(vk::Extent3D { width: image.extent.width, height: image.extent.height, depth: 1 })];
    let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
    unsafe { ctx.device.cmd_copy_image_to_buffer(cmd, image.raw, src, buffer, &region) };
}

/// The copies recorded before it become visible to the host (read after the submission's fence).
pub fn copy_to_host_barrier(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
        (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
    );
}

/// A global memory barrier (buffers, and images that keep their layout).
pub fn memory_barrier(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let b = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
}
