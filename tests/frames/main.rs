//! Frames in flight under synchronization validation across submissions.
//! Its own crate: the check is switched on through VK_LAYER_ENABLES, which
//! is read when an instance is created, so it would reach every test of a
//! shared binary.

#[path = "../common/mod.rs"]
mod common;

mod frame_ring;
mod frames_in_flight;

/// A context with synchronization validation across submissions as well:
/// the hazards a frame ring must prevent are between one frame's submission
/// and the next, which the validation layer here (1.3.239) checks only with
/// this ALPHA check, read from the environment when the instance is created.
fn sync_validated_across_submits() -> common::ValidatedContext {
    std::env::set_var(
        "VK_LAYER_ENABLES",
        "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT:\
         VALIDATION_CHECK_ENABLE_SYNCHRONIZATION_VALIDATION_QUEUE_SUBMIT",
    );
    common::sync_validated_context()
}
