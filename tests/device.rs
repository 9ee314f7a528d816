//! Device creation with validation, and the capability report.
mod common;

use hybrid_rt::app::{info_command, GpuOptions};

#[test]
fn validated_device_and_capability_report() {
    let ctx = common::validated_context();
    let caps = &ctx.caps;
    assert!(caps.api_version >= ash::vk::API_VERSION_1_3);
    assert!(caps.unusable.is_none());
    let report = caps.report();
    for needle in ["acceleration structures", "ray query", "ray-tracing pipeline", "Vulkan API"] {
        assert!(report.contains(needle), "report lacks '{needle}':\n{report}");
    }
    // Everything the context created carries a name and no error was reported.
    common::assert_validation_clean(&ctx);
}

#[test]
fn info_lists_the_selected_device() {
    let s = info_command(&GpuOptions { validation: true, ..Default::default() }).unwrap();
    assert!(s.contains("(selected)"), "{s}");
}

#[test]
fn ray_tracing_can_be_switched_off() {
    let ctx =
        GpuOptions { validation: true, disable_ray_tracing: true, ..Default::default() }.context().unwrap();
    assert!(!ctx.rt.acceleration_structure && !ctx.rt.ray_query && !ctx.rt.ray_tracing_pipeline);
    assert!(ctx.accel.is_none());
    common::assert_validation_clean(&ctx);
}
