//! The anti-aliasing stage after tone mapping (DESIGN.md: tonemap -> aa): its output target, which LDR
//! target is final, and when a technique is left out. At most one of `edge_aa` and `fxaa` runs, on the
//! 8-bit tone-mapped image: on HDR values a few bright pixels would dominate an edge.

use ash::vk;

use super::tonemap::LDR;
use crate::render::shading::{AaMode, ShadingConfig};
use crate::render::targets::TargetDesc;

/// The anti-aliased displayable frame (sRGB-encoded values, like `LDR`).
pub static AA_LDR: TargetDesc = TargetDesc::new("anti-aliased output", vk::Format::R8G8B8A8_UNORM);

/// The frame's final LDR image (read back, presented, screenshotted): tone mapping's output when no
/// anti-aliasing runs.
pub fn final_ldr(c: &ShadingConfig) -> &'static TargetDesc {
    if runs(c) {
        &AA_LDR
    } else {
        &LDR
    }
}

fn runs(c: &ShadingConfig) -> bool {
    !c.debug_view && c.aa != AaMode::None
}

/// Why the pass of technique `mine` is left out (None: it runs).
pub fn skip(c: &ShadingConfig, mine: AaMode) -> Option<&'static str> {
    if c.debug_view {
        // A debug view shows G-buffer values; blurring them would show
        // values no pixel has.
        Some("a debug view is shown unfiltered")
    } else if c.aa == AaMode::None {
        Some("--aa none")
    } else if c.aa != mine {
        Some(match c.aa {
            AaMode::Edge => "--aa edge runs the edge filter",
            _ => "--aa fxaa runs FXAA",
        })
    } else {
        None
    }
}
