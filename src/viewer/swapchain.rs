//! The window's surface and its swapchain: creation, recreation on resize / `ERROR_OUT_OF_DATE_KHR` /
//! `SUBOPTIMAL_KHR`, and the per-image render-finished semaphores presentation waits on.
//!
//! A zero-sized surface (a minimized window) has no swapchain extent: [`Presenter::recreate`] then keeps
//! the old swapchain and reports "paused", and the viewer stops rendering until the window has an area.

use anyhow::{bail, Context as _, Result};
use ash::{khr, vk};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

use crate::vk::Context;

/// The present mode asked for on the command line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PresentMode {
    /// Vsync, always available.
    #[default]
    Fifo,
    /// Vsync without blocking: the newest frame replaces a queued one.
    Mailbox,
    /// No vsync (may tear).
    Immediate,
}

impl PresentMode {
    pub fn vk(self) -> vk::PresentModeKHR {
        match self {
            PresentMode::Fifo => vk::PresentModeKHR::FIFO,
            PresentMode::Mailbox => vk::PresentModeKHR::MAILBOX,
            PresentMode::Immediate => vk::PresentModeKHR::IMMEDIATE,
        }
    }
}

/// `wanted` when the surface offers it, else FIFO (which every surface has).
pub fn choose_present_mode(wanted: PresentMode, available: &[vk::PresentModeKHR]) -> vk::PresentModeKHR {
    let w = wanted.vk();
    if available.contains(&w) {
        w
    } else {
        log::warn!(
            "present mode {wanted:?} is not supported by this surface (it offers {available:?}): falling back to FIFO"
        );
        vk::PresentModeKHR::FIFO
    }
}

/// The tone-mapped image already holds sRGB-encoded bytes, so a UNORM
/// swapchain shows them unchanged (a blit into an `_SRGB` image would encode
/// them a second time). B8G8R8A8 or R8G8B8A8 UNORM first; the blit swizzles.
pub fn choose_format(formats: &[vk::SurfaceFormatKHR]) -> Result<vk::SurfaceFormatKHR> {
    let preferred =
        [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM, vk::Format::A8B8G8R8_UNORM_PACK32];
    for want in preferred {
        if let Some(f) = formats
            .iter()
            .find(|f| f.format == want && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .or_else(|| formats.iter().find(|f| f.format == want))
        {
            return Ok(*f);
        }
    }
    let f = *formats.first().context("the surface reports no formats")?;
    log::warn!(
        "no UNORM 8-bit swapchain format (surface offers {:?}); using {:?}: colours may look too bright",
        formats.iter().map(|f| f.format).collect::<Vec<_>>(),
        f.format
    );
    Ok(f)
}

/// The swapchain extent for a surface: its current extent when it has one, else the window size clamped to
/// what the surface allows. Zero when the window has no area (minimized).
pub fn choose_extent(caps: &vk::SurfaceCapabilitiesKHR, window: vk::Extent2D) -> vk::Extent2D {
    if caps.current_extent.width != u32::MAX {
        return caps.current_extent;
    }
    if window.width == 0 || window.height == 0 {
        return vk::Extent2D { width: 0, height: 0 };
    }
    vk::Extent2D {
        width: window.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width.max(1)),
        height: window.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height.max(1)),
    }
}

/// What acquiring a swapchain image gave.
pub enum Acquired {
    /// Image index; `suboptimal` asks for a recreation after this frame.
    Image { index: u32, suboptimal: bool },
    /// The swapchain no longer matches the surface: recreate, skip the frame.
    OutOfDate,
}

/// Surface + swapchain + the swapchain images' semaphores.
pub struct Presenter {
    surface_loader: khr::surface::Instance,
    swapchain_loader: khr::swapchain::Device,
    pub surface: vk::SurfaceKHR,
    pub swapchain: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub format: vk::SurfaceFormatKHR,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
    wanted_mode: PresentMode,
    /// One per swapchain image, signalled by the submit rendering into it and waited on by its present.
    /// Per image, not per frame in flight: an image's semaphore is reused only once that image is acquired
    /// again, so the presentation engine is done with it (validation's reuse check).
    pub render_finished: Vec<vk::Semaphore>,
    generation: u32,
}

impl Presenter {
    /// Creates the window's surface and checks that the context's queue can
    /// present to it. The swapchain comes with the first [`Presenter::recreate`].
    pub fn new<W: HasDisplayHandle + HasWindowHandle>(
        ctx: &Context,
        window: &W,
        wanted_mode: PresentMode,
    ) -> Result<Presenter> {
        let display = window.display_handle().context("window display handle")?.as_raw();
        let handle = window.window_handle().context("window handle")?.as_raw();
        let entry = &ctx.instance.entry;
        let instance = &ctx.instance.raw;
        // SAFETY: the handles belong to `window`, which the viewer keeps alive
        // until after the surface is destroyed.
        let surface = unsafe { ash_window::create_surface(entry, instance, display, handle, None) }
            .context("creating the window surface (vkCreate*SurfaceKHR)")?;
        let surface_loader = khr::surface::Instance::new(entry, instance);
        let supported = unsafe {
            surface_loader.get_physical_device_surface_support(ctx.physical_device, ctx.queue_family, surface)
        };
        match supported {
            Ok(true) => {}
            Ok(false) | Err(_) => {
                unsafe { surface_loader.destroy_surface(surface, None) };
                bail!(
                    "device '{}' cannot present to this window from its graphics queue family {} \
                     (vkGetPhysicalDeviceSurfaceSupportKHR: {:?}); pick another device with --device",
                    ctx.caps.name,
                    ctx.queue_family,
                    supported
                );
            }
        }
        ctx.name(surface, "window surface");
        let swapchain_loader = khr::swapchain::Device::new(instance, &ctx.device);
        Ok(Presenter {
            surface_loader,
            swapchain_loader,
            surface,
            swapchain: vk::SwapchainKHR::null(),
            images: Vec::new(),
            format: vk::SurfaceFormatKHR::default(),
            extent: vk::Extent2D::default(),
            present_mode: vk::PresentModeKHR::FIFO,
            wanted_mode,
            render_finished: Vec::new(),
            generation: 0,
        })
    }

    pub fn has_swapchain(&self) -> bool {
        self.swapchain != vk::SwapchainKHR::null()
    }

    /// (Re)creates the swapchain for the surface's current size. Returns `false`, keeping the old one, when
    /// the surface has no area (minimized): the caller pauses. The caller has waited for the device to be
    /// idle (nothing may still use the old images or semaphores).
    pub fn recreate(&mut self, ctx: &Context, window: vk::Extent2D) -> Result<bool> {
        let pd = ctx.physical_device;
        let (caps, formats, modes) = unsafe {
            (
                self.surface_loader
                    .get_physical_device_surface_capabilities(pd, self.surface)
                    .context("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?,
                self.surface_loader
                    .get_physical_device_surface_formats(pd, self.surface)
                    .context("vkGetPhysicalDeviceSurfaceFormatsKHR")?,
                self.surface_loader
                    .get_physical_device_surface_present_modes(pd, self.surface)
                    .context("vkGetPhysicalDeviceSurfacePresentModesKHR")?,
            )
        };
        let extent = choose_extent(&caps, window);
        if extent.width == 0 || extent.height == 0 {
            return Ok(false);
        }
        if !caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_DST) {
            bail!(
                "the surface's swapchain images cannot be a transfer destination (needed to blit the frame)"
            );
        }
        let format = choose_format(&formats)?;
        let present_mode = if self.generation == 0 || self.present_mode != vk::PresentModeKHR::FIFO {
            choose_present_mode(self.wanted_mode, &modes)
        } else {
            // Already fell back once; don't log again on every resize.
            vk::PresentModeKHR::FIFO
        };
        let mut image_count = caps.min_image_count + 1;
        if caps.max_image_count != 0 {
            image_count = image_count.min(caps.max_image_count);
        }
        let composite_alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|a| caps.supported_composite_alpha.contains(*a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let old = self.swapchain;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(image_count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(composite_alpha)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old);
        let swapchain = unsafe { self.swapchain_loader.create_swapchain(&info, None) }
            .with_context(|| format!("vkCreateSwapchainKHR ({}x{})", extent.width, extent.height))?;
        self.destroy_swapchain(ctx);
        self.swapchain = swapchain;
        self.generation += 1;
        ctx.name(swapchain, &format!("swapchain #{}", self.generation));
        self.images = unsafe { self.swapchain_loader.get_swapchain_images(swapchain) }
            .context("vkGetSwapchainImagesKHR")?;
        for (i, img) in self.images.iter().enumerate() {
            ctx.name(*img, &format!("swapchain #{} image {i}", self.generation));
        }
        for i in 0..self.images.len() {
            let s = unsafe { ctx.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                .context("vkCreateSemaphore")?;
            ctx.name(s, &format!("render finished (swapchain image {i})"));
            self.render_finished.push(s);
        }
        self.format = format;
        self.extent = extent;
        self.present_mode = present_mode;
        log::info!(
            "swapchain {}x{}: {} images, {:?} {:?}, {:?}",
            extent.width,
            extent.height,
            self.images.len(),
            format.format,
            format.color_space,
            present_mode
        );
        Ok(true)
    }

    /// Acquires the next image, signalling `semaphore` when it is ready.
    pub fn acquire(&self, semaphore: vk::Semaphore) -> Result<Acquired> {
        match unsafe {
            self.swapchain_loader.acquire_next_image(self.swapchain, u64::MAX, semaphore, vk::Fence::null())
        } {
            Ok((index, suboptimal)) => Ok(Acquired::Image { index, suboptimal }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(e) => Err(e).context("vkAcquireNextImageKHR"),
        }
    }

    /// Presents image `index` once its render-finished semaphore is signalled.
    /// Returns whether the swapchain should be recreated.
    pub fn present(&self, queue: vk::Queue, index: u32) -> Result<bool> {
        let waits = [self.render_finished[index as usize]];
        let swapchains = [self.swapchain];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        match unsafe { self.swapchain_loader.queue_present(queue, &info) } {
            Ok(suboptimal) => Ok(suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(true),
            Err(e) => Err(e).context("vkQueuePresentKHR"),
        }
    }

    fn destroy_swapchain(&mut self, ctx: &Context) {
        for s in self.render_finished.drain(..) {
            unsafe { ctx.device.destroy_semaphore(s, None) };
        }
        self.images.clear();
        if self.swapchain != vk::SwapchainKHR::null() {
            unsafe { self.swapchain_loader.destroy_swapchain(self.swapchain, None) };
            self.swapchain = vk::SwapchainKHR::null();
        }
    }

    /// Destroys the swapchain and the surface (the device is idle).
    pub fn destroy(&mut self, ctx: &Context) {
        self.destroy_swapchain(ctx);
        if self.surface != vk::SurfaceKHR::null() {
            unsafe { self.surface_loader.destroy_surface(self.surface, None) };
            self.surface = vk::SurfaceKHR::null();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sf(format: vk::Format) -> vk::SurfaceFormatKHR {
        vk::SurfaceFormatKHR { format, color_space: vk::ColorSpaceKHR::SRGB_NONLINEAR }
    }

    #[test]
    fn prefers_a_unorm_format_over_srgb() {
        let f = choose_format(&[sf(vk::Format::B8G8R8A8_SRGB), sf(vk::Format::B8G8R8A8_UNORM)]).unwrap();
        assert_eq!(f.format, vk::Format::B8G8R8A8_UNORM);
        let f = choose_format(&[sf(vk::Format::R8G8B8A8_SRGB), sf(vk::Format::R8G8B8A8_UNORM)]).unwrap();
        assert_eq!(f.format, vk::Format::R8G8B8A8_UNORM);
        assert!(choose_format(&[]).is_err());
    }

    #[test]
    fn unsupported_present_mode_falls_back_to_fifo() {
        let modes = [vk::PresentModeKHR::FIFO, vk::PresentModeKHR::IMMEDIATE];
        assert_eq!(choose_present_mode(PresentMode::Immediate, &modes), vk::PresentModeKHR::IMMEDIATE);
        assert_eq!(choose_present_mode(PresentMode::Mailbox, &modes), vk::PresentModeKHR::FIFO);
        assert_eq!(choose_present_mode(PresentMode::Fifo, &modes), vk::PresentModeKHR::FIFO);
    }

    #[test]
    fn extent_follows_the_surface_and_is_zero_when_minimized() {
        let mut caps = vk::SurfaceCapabilitiesKHR {
            current_extent: vk::Extent2D { width: 300, height: 200 },
            min_image_extent: vk::Extent2D { width: 1, height: 1 },
            max_image_extent: vk::Extent2D { width: 4096, height: 4096 },
            ..Default::default()
        };
        let win = vk::Extent2D { width: 640, height: 480 };
        assert_eq!(choose_extent(&caps, win), vk::Extent2D { width: 300, height: 200 });
        caps.current_extent = vk::Extent2D { width: u32::MAX, height: u32::MAX };
        assert_eq!(choose_extent(&caps, win), win);
        assert_eq!(choose_extent(&caps, vk::Extent2D { width: 0, height: 480 }).width, 0);
        caps.current_extent = vk::Extent2D { width: 0, height: 0 };
        assert_eq!(choose_extent(&caps, win).width, 0);
    }
}
