//! Where each mesh primitive lives in the scene's buffers and how the
//! G-buffer draws it: shared by `scene.rs`, which fills them, and
//! `clusters.rs`, which splits draws into clusters.

use crate::scene::AlphaMode;

/// Where one mesh primitive lives in the shared buffers.
#[derive(Clone, Copy, Debug)]
pub struct PrimitiveRange {
    pub first_index: u32,
    pub index_count: u32,
    pub vertex_offset: u32,
    pub vertex_count: u32,
}

/// One draw of the G-buffer pass.
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub instance: u32,
    pub range: PrimitiveRange,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
}
