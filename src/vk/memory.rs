//! Buffers and images on gpu-allocator, each created with a debug name. Resources are destroyed explicitly
//! (`destroy(ctx)`): they need the device, and a frame owns them in a known order.

use anyhow::{Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::{built, image_barrier, Context};

pub struct Buffer {
    pub raw: vk::Buffer,
    pub allocation: Option<Allocation>,
    pub size: u64,
    /// Device address when created with SHADER_DEVICE_ADDRESS, else 0.
    pub address: vk::DeviceAddress,
}

/// The most host memory a buffer upload stages at once (textures batch the same way).
pub const STAGING_BYTES: usize = 64 << 20;

/// Device memory from the allocator, or the failure a test injected (`Context::alloc_fault`).
fn allocate(ctx: &Context, desc: &AllocationCreateDesc) -> Result<Allocation> {
    if ctx.alloc_fault.hit() {
        anyhow::bail!("out of device memory (injected by a test)");
    }
    Ok(ctx.allocator.lock().unwrap().allocate(desc)?)
}

impl Buffer {
    /// A buffer that owns nothing (a placeholder; `destroy` is a no-op).
    pub fn null() -> Buffer {
        Buffer { raw: vk::Buffer::null(), allocation: None, size: 0, address: 0 }
    }

    pub fn new(
        ctx: &Context,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Buffer> {
        let size = size.max(4);
        let raw = unsafe {
            ctx.device.create_buffer(&vk::BufferCreateInfo::default().size(size).usage(usage), None)
        }
        .with_context(|| format!("create buffer '{name}'"))?;
        let req = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let allocation = allocate(
            ctx,
            &AllocationCreateDesc {
                name,
                requirements: req,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            },
        )
        .inspect_err(|_| unsafe { ctx.device.destroy_buffer(raw, None) })
        .with_context(|| format!("allocate {size} bytes for buffer '{name}'"))?;
        unsafe { ctx.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset())? };
        ctx.name(raw, name);
        let address = if usage.contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS) {
            unsafe {
                ctx.device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(raw))
            }
        } else {
            0
        };
        Ok(Buffer { raw, allocation: Some(allocation), size, address })
    }

    /// A device-local buffer filled from `data` through a staging copy.
    pub fn with_data(ctx: &Context, name: &str, data: &[u8], usage: vk::BufferUsageFlags) -> Result<Buffer> {
        let usage = usage | vk::BufferUsageFlags::TRANSFER_DST;
        let buf = Buffer::new(ctx, name, data.len() as u64, usage, MemoryLocation::GpuOnly)?;
        super::built(ctx, buf, |b| if data.is_empty() { Ok(()) } else { b.upload(ctx, 0, data) })
    }

    /// Copies `data` into a device-local buffer (made by `with_data`) at
    /// `offset` through a staging buffer of at most [`STAGING_BYTES`],
    /// one copy per chunk, waiting for each: a 200 MB vertex buffer does not
    /// hold a second 200 MB of host memory while it uploads (on a software
    /// device the "device" copy is host memory too).
    pub fn upload(&self, ctx: &Context, offset: u64, data: &[u8]) -> Result<()> {
        if data.is_empty() {
            return Ok(());
        }
        anyhow::ensure!(offset + data.len() as u64 <= self.size, "upload past the end of a buffer");
        let mut staging = Buffer::new(
            ctx,
            "upload (staging)",
            data.len().min(STAGING_BYTES) as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let mut r = Ok(());
        for (k, chunk) in data.chunks(STAGING_BYTES).enumerate() {
            let at = offset + (k * STAGING_BYTES) as u64;
            r = staging.write(0, chunk).and_then(|_| {
                ctx.one_shot("upload", |cmd| {
                    let region = [vk::BufferCopy::default().dst_offset(at).size(chunk.len() as u64)];
                    unsafe { ctx.device.cmd_copy_buffer(cmd, staging.raw, self.raw, &region) };
                    Ok(())
                })
            });
            if r.is_err() {
                break;
            }
        }
        staging.destroy(ctx);
        r
    }

    /// Writes into a host-visible buffer.
    pub fn write(&mut self, offset: usize, data: &[u8]) -> Result<()> {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .context("buffer is not host visible")?;
        slice
            .get_mut(offset..offset + data.len())
            .context("write past the end of a buffer")?
            .copy_from_slice(data);
        Ok(())
    }

    pub fn read(&self) -> Result<&[u8]> {
        self.allocation.as_ref().and_then(|a| a.mapped_slice()).context("buffer is not host visible")
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if let Some(a) = self.allocation.take() {
            unsafe { ctx.device.destroy_buffer(self.raw, None) };
            let _ = ctx.allocator.lock().unwrap().free(a);
        }
    }
}

/// One texture for [`Image::textures`]: tightly packed texels of `format`.
pub struct TextureDesc<'a> {
    pub name: String,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub texels: &'a [u8],
    pub mipmaps: bool,
}

pub struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub allocation: Option<Allocation>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub mip_levels: u32,
    pub aspect: vk::ImageAspectFlags,
}

impl Image {
    /// An image that owns nothing (a placeholder; `destroy` is a no-op).
    pub fn null() -> Image {
        Image {
            raw: vk::Image::null(),
            view: vk::ImageView::null(),
            allocation: None,
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D::default(),
            mip_levels: 0,
            aspect: vk::ImageAspectFlags::empty(),
        }
    }

    pub fn new_2d(
        ctx: &Context,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        mip_levels: u32,
        usage: vk::ImageUsageFlags,
    ) -> Result<Image> {
        Image::create(ctx, name, format, extent, mip_levels, None, usage)
    }

    /// A 2D array of `layers` layers, one mip level, viewed whole as a 2D array.
    pub fn new_2d_array(
        ctx: &Context,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        layers: u32,
        usage: vk::ImageUsageFlags,
    ) -> Result<Image> {
        Image::create(ctx, name, format, extent, 1, Some(layers), usage)
    }

    /// `array`: Some(layers) for a 2D-array view, None for a plain 2D image.
    fn create(
        ctx: &Context,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        mip_levels: u32,
        array: Option<u32>,
        usage: vk::ImageUsageFlags,
    ) -> Result<Image> {
        let layers = array.unwrap_or(1).max(1);
        let aspect = match format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
            _ => vk::ImageAspectFlags::COLOR,
        };
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: extent.width.max(1), height: extent.height.max(1), depth: 1 })
            .mip_levels(mip_levels)
            .array_layers(layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { ctx.device.create_image(&info, None) }.with_context(|| {
            format!("create image '{name}' ({format:?} {}x{})", extent.width, extent.height)
        })?;
        let req = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let allocation = allocate(
            ctx,
            &AllocationCreateDesc {
                name,
                requirements: req,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            },
        )
        .inspect_err(|_| unsafe { ctx.device.destroy_image(raw, None) })
        .with_context(|| format!("allocate image '{name}'"))?;
        // From here the image owns its memory: a failure destroys both.
        let image = Image {
            raw,
            view: vk::ImageView::null(),
            allocation: Some(allocation),
            format,
            extent,
            mip_levels,
            aspect,
        };
        let image = super::built(ctx, image, |image| {
            let a = image.allocation.as_ref().expect("allocated above");
            unsafe { ctx.device.bind_image_memory(raw, a.memory(), a.offset()) }?;
            let info = vk::ImageViewCreateInfo::default()
                .image(raw)
                .view_type(if array.is_some() {
                    vk::ImageViewType::TYPE_2D_ARRAY
                } else {
                    vk::ImageViewType::TYPE_2D
                })
                .format(format)
                .subresource_range(
                    vk::ImageSubresourceRange::default()
                        .aspect_mask(aspect)
                        .level_count(mip_levels)
                        .layer_count(layers),
                );
            image.view = unsafe { ctx.device.create_image_view(&info, None) }?;
            Ok(())
        })
        .with_context(|| format!("bind memory / create view of image '{name}'"))?;
        ctx.name(raw, name);
        ctx.name(image.view, &format!("{name} view"));
        Ok(image)
    }

    /// A sampled texture whose mip levels are given (`levels[k]`: level k's tightly packed texels, its
    /// extent the base halved k times), for chains a blit cannot make (gpu/env_prefilter.rs). Ends in
    /// SHADER_READ_ONLY_OPTIMAL.
    pub fn texture_levels(
        ctx: &Context,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        levels: &[Vec<u8>],
    ) -> Result<Image> {
        let mut offsets = Vec::with_capacity(levels.len());
        let mut size = 0u64;
        for l in levels {
            offsets.push(size);
            size += (l.len() as u64).div_ceil(16) * 16;
        }
        let mut staging = Buffer::new(
            ctx,
            &format!("{name} (staging)"),
            size,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let image = Image::new_2d(ctx, name, format, extent, levels.len() as u32, usage).and_then(|image| {
            built(ctx, image, |image| {
                for (l, &o) in levels.iter().zip(&offsets) {
                    staging.write(o as usize, l)?;
                }
                ctx.one_shot(&format!("upload {name}"), |cmd| {
                    image.record_upload_levels(ctx, cmd, staging.raw, &offsets);
                    Ok(())
                })
            })
        });
        staging.destroy(ctx);
        image
    }

    /// Copies level k from `src` at `offsets[k]`, leaves every level shader-readable.
    fn record_upload_levels(&self, ctx: &Context, cmd: vk::CommandBuffer, src: vk::Buffer, offsets: &[u64]) {
        let transfer = (vk::PipelineStageFlags2::TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
        let (undefined, dst) = (vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        image_barrier(
            ctx,
            cmd,
            self.raw,
            self.aspect,
            undefined,
            dst,
            (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
            transfer,
        );
        let copies: Vec<_> = offsets
            .iter()
            .enumerate()
            .map(|(k, &o)| {
                let (w, h) = ((self.extent.width >> k).max(1), (self.extent.height >> k).max(1));
                vk::BufferImageCopy::default()
                    .buffer_offset(o)
                    .image_subresource(
                        vk::ImageSubresourceLayers::default()
                            .aspect_mask(self.aspect)
                            .mip_level(k as u32)
                            .layer_count(1),
                    )
                    .image_extent(vk::Extent3D { width: w, height: h, depth: 1 })
            })
            .collect();
        unsafe { ctx.device.cmd_copy_buffer_to_image(cmd, src, self.raw, dst, &copies) };
        let read = (
            vk::PipelineStageFlags2::FRAGMENT_SHADER | vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_SAMPLED_READ,
        );
        image_barrier(
            ctx,
            cmd,
            self.raw,
            self.aspect,
            dst,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            transfer,
            read,
        );
    }

    /// A sampled texture from tightly packed texels, with a full mip chain generated by linear blits when
    /// `mipmaps` is set. Ends in SHADER_READ_ONLY_OPTIMAL.
    pub fn texture(
        ctx: &Context,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        texels: &[u8],
        mipmaps: bool,
    ) -> Result<Image> {
        let desc = TextureDesc { name: name.to_string(), format, extent, texels, mipmaps };
        Ok(Image::textures(ctx, &[desc])?.pop().unwrap())
    }

    /// Several textures (as [`Image::texture`]) uploaded through shared staging buffers: one submission per
    /// ~64 MiB of texels rather than one per texture.
    pub fn textures(ctx: &Context, descs: &[TextureDesc]) -> Result<Vec<Image>> {
        const BATCH_BYTES: usize = STAGING_BYTES;
        built(ctx, Vec::with_capacity(descs.len()), |images| {
            let mut start = 0;
            while start < descs.len() {
                // Take textures until the batch is full (at least one).
                let mut end = start + 1;
                let mut bytes = descs[start].texels.len();
                while end < descs.len() && bytes + descs[end].texels.len() <= BATCH_BYTES {
                    bytes += descs[end].texels.len();
                    end += 1;
                }
                images.extend(Image::upload_batch(ctx, &descs[start..end])?);
                start = end;
            }
            Ok(())
        })
    }

    fn upload_batch(ctx: &Context, descs: &[TextureDesc]) -> Result<Vec<Image>> {
        // Buffer-to-image copies want offsets aligned to the texel size (4).
        let mut offsets = Vec::with_capacity(descs.len());
        let mut size = 0u64;
        for d in descs {
            offsets.push(size);
            size += (d.texels.len() as u64).div_ceil(16) * 16;
        }
        let mut staging = Buffer::new(
            ctx,
            &format!("{} texture(s) (staging)", descs.len()),
            size,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let images = built(ctx, Vec::with_capacity(descs.len()), |images| {
            for d in descs {
                let e = d.extent;
                let levels = if d.mipmaps { 32 - e.width.max(e.height).max(1).leading_zeros() } else { 1 };
                let usage = vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_DST
                    | vk::ImageUsageFlags::TRANSFER_SRC;
                images.push(Image::new_2d(ctx, &d.name, d.format, e, levels, usage)?);
            }
            for (d, &o) in descs.iter().zip(&offsets) {
                staging.write(o as usize, d.texels)?;
            }
            ctx.one_shot(&format!("upload {} texture(s)", descs.len()), |cmd| {
                for (img, &o) in images.iter().zip(&offsets) {
                    img.record_upload(ctx, cmd, staging.raw, o);
                }
                Ok(())
            })
        });
        staging.destroy(ctx);
        images
    }

    /// Copies level 0 from `src` at `offset`, blits the mip chain, leaves it shader-readable.
    pub fn record_upload(&self, ctx: &Context, cmd: vk::CommandBuffer, src: vk::Buffer, offset: u64) {
        let d = &ctx.device;
        let transfer = (vk::PipelineStageFlags2::TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
        image_barrier(
            ctx,
            cmd,
            self.raw,
            self.aspect,
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
            transfer,
        );
        let copy = [vk::BufferImageCopy::default()
            .buffer_offset(offset)
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(self.aspect).mip_level(0).layer_count(1),
            )
            .image_extent(vk::Extent3D { width: self.extent.width, height: self.extent.height, depth: 1 })];
        unsafe {
            d.cmd_copy_buffer_to_image(cmd, src, self.raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &copy)
        };
        let (mut w, mut h) = (self.extent.width as i32, self.extent.height as i32);
        for level in 1..self.mip_levels {
            let sub = |l: u32| {
                vk::ImageSubresourceRange::default()
                    .aspect_mask(self.aspect)
                    .base_mip_level(l)
                    .level_count(1)
                    .layer_count(1)
            };
            // Previous level: transfer dst -> transfer src.
            let b = [vk::ImageMemoryBarrier2::default()
                .image(self.raw)
                .subresource_range(sub(level - 1))
                .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                .src_stage_mask(vk::PipelineStageFlags2::TRANSFER)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::TRANSFER)
                .dst_access_mask(vk::AccessFlags2::TRANSFER_READ)];
            unsafe { d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&b)) };
            let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
            let layers = |l: u32| {
                vk::ImageSubresourceLayers::default().aspect_mask(self.aspect).mip_level(l).layer_count(1)
            };
            let blit = [vk::ImageBlit::default()
                .src_subresource(layers(level - 1))
                .src_offsets([vk::Offset3D::default(), vk::Offset3D { x: w, y: h, z: 1 }])
                .dst_subresource(layers(level))
                .dst_offsets([vk::Offset3D::default(), vk::Offset3D { x: nw, y: nh, z: 1 }])];
            unsafe {
                d.cmd_blit_image(
                    cmd,
                    self.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    self.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &blit,
                    vk::Filter::LINEAR,
                )
            };
            w = nw;
            h = nh;
        }
        // All levels but the last are TRANSFER_SRC now; the last is TRANSFER_DST.
        let to_read = |base: u32, count: u32, old: vk::ImageLayout, src_access: vk::AccessFlags2| {
            vk::ImageMemoryBarrier2::default()
                .image(self.raw)
                .subresource_range(
                    vk::ImageSubresourceRange::default()
                        .aspect_mask(self.aspect)
                        .base_mip_level(base)
                        .level_count(count)
                        .layer_count(1),
                )
                .old_layout(old)
                .new_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
                .src_stage_mask(vk::PipelineStageFlags2::TRANSFER)
                .src_access_mask(src_access)
                .dst_stage_mask(
                    vk::PipelineStageFlags2::FRAGMENT_SHADER | vk::PipelineStageFlags2::COMPUTE_SHADER,
                )
                .dst_access_mask(vk::AccessFlags2::SHADER_SAMPLED_READ)
        };
        let last = self.mip_levels - 1;
        let mut barriers =
            vec![to_read(last, 1, vk::ImageLayout::TRANSFER_DST_OPTIMAL, vk::AccessFlags2::TRANSFER_WRITE)];
        if last > 0 {
            barriers.push(to_read(
                0,
                last,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::AccessFlags2::TRANSFER_READ,
            ));
        }
        unsafe {
            d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers))
        };
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if let Some(a) = self.allocation.take() {
            unsafe {
                ctx.device.destroy_image_view(self.view, None);
                ctx.device.destroy_image(self.raw, None);
            }
            let _ = ctx.allocator.lock().unwrap().free(a);
        }
    }
}

crate::destroy_by_method!(Buffer, Image);
