//! Per-resolution render targets: the G-buffer (MRT + reversed-Z depth), the
//! linear HDR radiance image and the tone-mapped 8-bit output.

use anyhow::Result;
use ash::vk;

use crate::vk::{Context, Image};

/// G-buffer formats, in attachment order (matches gbuffer.frag's outputs).
pub const GBUFFER_FORMATS: [(vk::Format, &str); 5] = [
    (vk::Format::R8G8B8A8_SRGB, "gbuffer albedo+occlusion"),
    (vk::Format::R16G16B16A16_SFLOAT, "gbuffer normal+roughness"),
    (vk::Format::R8G8B8A8_UNORM, "gbuffer metallic+transmission+ior"),
    (vk::Format::R16G16B16A16_SFLOAT, "gbuffer emissive"),
    (vk::Format::R32G32_UINT, "gbuffer hit (instance, primitive)"),
];
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
pub const HDR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const LDR_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

pub struct Targets {
    pub extent: vk::Extent2D,
    pub gbuffer: Vec<Image>,
    pub depth: Image,
    pub hdr: Image,
    pub ldr: Image,
}

impl Targets {
    pub fn new(ctx: &Context, extent: vk::Extent2D) -> Result<Targets> {
        let color = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let gbuffer = GBUFFER_FORMATS
            .iter()
            .map(|(f, name)| Image::new_2d(ctx, name, *f, extent, 1, color))
            .collect::<Result<Vec<_>>>()?;
        let depth = Image::new_2d(
            ctx,
            "gbuffer depth (reversed-Z)",
            DEPTH_FORMAT,
            extent,
            1,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
        )?;
        let hdr = Image::new_2d(
            ctx,
            "hdr radiance",
            HDR_FORMAT,
            extent,
            1,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
        )?;
        let ldr = Image::new_2d(
            ctx,
            "tonemapped output",
            LDR_FORMAT,
            extent,
            1,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
        )?;
        Ok(Targets { extent, gbuffer, depth, hdr, ldr })
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for i in self.gbuffer.iter_mut().chain([&mut self.depth, &mut self.hdr, &mut self.ldr]) {
            i.destroy(ctx);
        }
    }
}
