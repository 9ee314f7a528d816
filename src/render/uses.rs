//! What a pass declares: the render targets (`TargetDesc`) and shared buffers it uses and how
//! (`Access`). `frame.rs` derives barriers from these and `targets.rs` allocates from them; both import
//! this file, which imports neither.

use ash::vk;
use vk::AccessFlags2 as A;
use vk::PipelineStageFlags2 as S;

/// A render target: name (debug name, identity) and format.
#[derive(Debug, PartialEq, Eq)]
pub struct TargetDesc {
    pub name: &'static str,
    pub format: vk::Format,
    /// Its contents carry over from frame to frame (an accumulation): after its first use a frame starts
    /// from the last layout, not from undefined contents.
    pub kept: bool,
}

impl TargetDesc {
    pub const fn new(name: &'static str, format: vk::Format) -> TargetDesc {
        TargetDesc { name, format, kept: false }
    }

    /// A target whose contents are kept across frames.
    pub const fn kept(name: &'static str, format: vk::Format) -> TargetDesc {
        TargetDesc { name, format, kept: true }
    }
}

/// Buffers shared between passes, tracked like images (global barriers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SharedBuffer {
    /// The one vertex/index copy (the skinning pass writes its skinned ranges).
    Geometry,
    /// The tracer's acceleration data: TLAS/BLASes or the compute BVH.
    Accel,
    /// The auto-exposure state and the luminance reduction's scratch.
    Exposure,
    /// The frame counters (rays by kind, truncated and bad pixels).
    Counters,
    /// The ray-tracing budget's per-object statistics.
    Budget,
    /// Host-visible buffers a frame's images are copied into (readbacks).
    Readback,
}

/// How a pass uses a resource. Shader accesses happen in the pass's own
/// shader stage (compute or ray tracing), the rest in fixed stages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// texelFetch / texture from a sampled image.
    Sampled,
    /// imageLoad.
    StorageRead,
    /// imageStore (every pixel the readers read is written).
    StorageWrite,
    /// Colour attachment, cleared and written.
    ColorAttachment,
    /// Depth attachment, cleared, tested and written.
    DepthAttachment,
    /// Source of a copy or blit.
    TransferRead,
    /// Destination of a copy or blit (the viewer's swapchain image).
    TransferWrite,
    /// Handed to the presentation engine (an imported swapchain image's
    /// last use; no later access in the command buffer).
    Present,
    /// Read by the host after the submission's fence (a readback's last use).
    HostRead,
    /// Storage-buffer or acceleration-structure reads in shaders.
    ShaderRead,
    /// Storage-buffer writes in shaders.
    ShaderWrite,
    /// Vertex pulling and index fetch of a raster pass.
    VertexInput,
    /// Input of an acceleration-structure build.
    AsBuildRead,
    /// Acceleration-structure build or refit output (read too: refits).
    AsBuildWrite,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    Image(&'static TargetDesc),
    Buffer(SharedBuffer),
}

/// One declared use.
#[derive(Clone, Copy, Debug)]
pub struct Use {
    pub resource: Resource,
    pub access: Access,
    /// The pass also samples the image between its own barriers (the G-buffer pass's occlusion pyramid
    /// reads its depth): only then is the target allocated with SAMPLED usage too.
    pub sampled_within: bool,
}

impl Use {
    pub const fn image(t: &'static TargetDesc, access: Access) -> Use {
        Use { resource: Resource::Image(t), access, sampled_within: false }
    }
    pub const fn buffer(b: SharedBuffer, access: Access) -> Use {
        Use { resource: Resource::Buffer(b), access, sampled_within: false }
    }
    /// This use, with the pass sampling the image itself (`sampled_within`).
    pub const fn sampled_within(self) -> Use {
        Use { sampled_within: true, ..self }
    }
}

impl Access {
    pub fn writes(self) -> bool {
        matches!(
            self,
            Access::StorageWrite
                | Access::ColorAttachment
                | Access::DepthAttachment
                | Access::ShaderWrite
                | Access::AsBuildWrite
                | Access::TransferWrite
        )
    }

    /// Whether the previous contents are irrelevant (whole image overwritten).
    pub(super) fn discards(self) -> bool {
        matches!(self, Access::ColorAttachment | Access::DepthAttachment)
    }

    /// The image layout this access needs.
    pub fn layout(self) -> vk::ImageLayout {
        match self {
            Access::Sampled => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Access::ColorAttachment => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            Access::DepthAttachment => vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            Access::TransferRead => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            Access::TransferWrite => vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            Access::Present => vk::ImageLayout::PRESENT_SRC_KHR,
            _ => vk::ImageLayout::GENERAL,
        }
    }

    /// Stages and access flags, with `shader` the pass's shader stage(s).
    pub(super) fn scope(
        self,
        shader: vk::PipelineStageFlags2,
        accel: bool,
    ) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
        let as_read = if accel { A::ACCELERATION_STRUCTURE_READ_KHR } else { A::NONE };
        match self {
            Access::Sampled => (shader, A::SHADER_SAMPLED_READ),
            Access::StorageRead => (shader, A::SHADER_STORAGE_READ),
            Access::StorageWrite => (shader, A::SHADER_STORAGE_WRITE),
            Access::ColorAttachment => (S::COLOR_ATTACHMENT_OUTPUT, A::COLOR_ATTACHMENT_WRITE),
            Access::DepthAttachment => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
            ),
            Access::TransferRead => (S::COPY | S::BLIT, A::TRANSFER_READ),
            Access::TransferWrite => (S::COPY | S::BLIT, A::TRANSFER_WRITE),
            // Presentation waits on the frame's semaphore, not a stage.
            Access::Present => (S::BOTTOM_OF_PIPE, A::NONE),
            Access::HostRead => (S::HOST, A::HOST_READ),
            Access::ShaderRead => (shader, A::SHADER_READ | as_read),
            Access::ShaderWrite => (shader, A::SHADER_STORAGE_WRITE),
            Access::VertexInput => {
                (S::VERTEX_SHADER | S::INDEX_INPUT, A::SHADER_STORAGE_READ | A::INDEX_READ)
            }
            Access::AsBuildRead => (S::ACCELERATION_STRUCTURE_BUILD_KHR, A::SHADER_READ),
            Access::AsBuildWrite => (
                S::ACCELERATION_STRUCTURE_BUILD_KHR,
                A::ACCELERATION_STRUCTURE_READ_KHR | A::ACCELERATION_STRUCTURE_WRITE_KHR,
            ),
        }
    }
}
