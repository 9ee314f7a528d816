//! Per-resolution render targets. Each is described once (`TargetDesc`, next to the pass that writes
//! it); the frame allocates exactly the targets its recorded passes use, with the usage flags their
//! declared accesses need.

use anyhow::Result;
use ash::vk;

pub use super::uses::TargetDesc;
use super::uses::{Access, Resource, Use};
use crate::vk::{built, Context, Image};

/// One allocated target.
pub struct Target {
    pub desc: &'static TargetDesc,
    pub image: Image,
    /// A recorded frame has laid it out (GENERAL): a `kept` target's contents are defined from then on.
    pub laid_out: std::cell::Cell<bool>,
}

impl std::ops::Deref for Target {
    type Target = Image;
    fn deref(&self) -> &Image {
        &self.image
    }
}

impl Target {
    fn new(
        ctx: &Context,
        desc: &'static TargetDesc,
        usage: vk::ImageUsageFlags,
        extent: vk::Extent2D,
    ) -> Result<Target> {
        let image = Image::new_2d(ctx, desc.name, desc.format, extent, 1, usage)?;
        Ok(Target { desc, image, laid_out: std::cell::Cell::new(false) })
    }
}

pub struct Targets {
    pub extent: vk::Extent2D,
    targets: Vec<Target>,
}

fn usage(u: &Use) -> vk::ImageUsageFlags {
    use vk::ImageUsageFlags as U;
    let within = if u.sampled_within { U::SAMPLED } else { U::empty() };
    within
        | match u.access {
            Access::Sampled => U::SAMPLED,
            Access::StorageRead | Access::StorageWrite => U::STORAGE,
            Access::ColorAttachment => U::COLOR_ATTACHMENT,
            Access::DepthAttachment => U::DEPTH_STENCIL_ATTACHMENT,
            Access::TransferRead => U::TRANSFER_SRC,
            Access::TransferWrite => U::TRANSFER_DST,
            _ => U::empty(),
        }
}

impl Targets {
    /// No images yet.
    pub fn empty(extent: vk::Extent2D) -> Targets {
        Targets { extent, targets: Vec::new() }
    }

    /// Allocates every image that `uses` name, once each.
    pub fn new(ctx: &Context, extent: vk::Extent2D, uses: &[Use]) -> Result<Targets> {
        let mut wanted: Vec<(&'static TargetDesc, vk::ImageUsageFlags)> = Vec::new();
        for u in uses {
            let Resource::Image(t) = u.resource else { continue };
            match wanted.iter_mut().find(|(d, _)| d.name == t.name) {
                Some((_, flags)) => *flags |= usage(u),
                None => wanted.push((t, usage(u))),
            }
        }
        let out = built(ctx, Targets::empty(extent), |out| {
            for (desc, usage) in wanted {
                out.targets.push(Target::new(ctx, desc, usage, extent)?);
            }
            Ok(())
        })?;
        Ok(out)
    }

    pub fn get(&self, desc: &TargetDesc) -> Option<&Target> {
        self.targets.iter().find(|t| t.desc.name == desc.name)
    }

    /// Names and bytes per pixel of the allocated targets.
    pub fn describe(&self) -> Vec<(&'static str, u32)> {
        self.targets.iter().map(|t| (t.desc.name, bytes_per_pixel(t.desc.format))).collect()
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for t in &mut self.targets {
            t.image.destroy(ctx);
        }
        self.targets.clear();
    }
}

pub fn bytes_per_pixel(f: vk::Format) -> u32 {
    match f {
        vk::Format::R8G8B8A8_SRGB
        | vk::Format::R8G8B8A8_UNORM
        | vk::Format::D32_SFLOAT
        | vk::Format::R32_UINT => 4,
        vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_UINT => 8,
        vk::Format::R32G32B32A32_SFLOAT => 16,
        _ => 0,
    }
}

crate::destroy_by_method!(Targets);
