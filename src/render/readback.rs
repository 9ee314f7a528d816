//! The frame's readback: a pass that copies targets into host-visible
//! buffers, recorded after the frame's passes with the same recorder (so
//! its barriers follow from theirs). `render`, `report`, `bench` and the
//! tests read frames through it.

use anyhow::{Context as _, Result};
use ash::vk;

use super::frame::Recorder;
use super::targets::Targets;
use super::uses::{Access, TargetDesc, Use};
use crate::vk::{copy_image_to_buffer, memory_barrier, Context};

/// Records the pass `readback`: each target of `copies` into its buffer,
/// then the copies, and the counters and exposure state the frame's
/// shaders wrote, made visible to the host.
pub fn record(
    ctx: &Context,
    rec: &mut Recorder,
    targets: &Targets,
    copies: &[(&'static TargetDesc, vk::Buffer)],
) -> Result<()> {
    let uses: Vec<Use> = copies.iter().map(|(d, _)| Use::image(d, Access::TransferRead)).collect();
    rec.pass("readback", vk::PipelineStageFlags2::NONE, &uses, |cmd| {
        for (desc, buffer) in copies {
            let image =
                targets.get(desc).with_context(|| format!("{} is not a target of this frame", desc.name))?;
            copy_image_to_buffer(ctx, cmd, image, *buffer);
        }
        memory_barrier(
            ctx,
            cmd,
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_WRITE),
            (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
        );
        Ok(())
    })
}
