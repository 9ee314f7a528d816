//! The frame's readback: a pass copying targets into host-visible buffers, recorded after the frame's
//! passes with the same recorder (so its barriers follow from theirs). `render`, `report`, `bench` and
//! the tests read frames through it.

use anyhow::{Context as _, Result};
use ash::vk;

use super::frame::Recorder;
use super::targets::Targets;
use super::uses::{Access, SharedBuffer, TargetDesc, Use};
use crate::vk::{copy_image_to_buffer, Context};

/// Records the pass `readback`: each target of `copies` into its buffer
/// (host-visible), then the copies' hand-over to the host.
pub fn record(
    ctx: &Context,
    rec: &mut Recorder,
    targets: &Targets,
    copies: &[(&'static TargetDesc, vk::Buffer)],
) -> Result<()> {
    let mut uses: Vec<Use> = copies.iter().map(|(d, _)| Use::image(d, Access::TransferRead)).collect();
    uses.push(Use::buffer(SharedBuffer::Readback, Access::TransferWrite));
    rec.pass("readback", vk::PipelineStageFlags2::NONE, &uses, |cmd| {
        for (desc, buffer) in copies {
            let image =
                targets.get(desc).with_context(|| format!("{} is not a target of this frame", desc.name))?;
            copy_image_to_buffer(ctx, cmd, image, *buffer);
        }
        Ok(())
    })?;
    rec.transition(&[Use::buffer(SharedBuffer::Readback, Access::HostRead)])
}
