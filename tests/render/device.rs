//! Device creation with validation, the capability report, and validation
//! errors counted through teardown.
use crate::common;

use hybrid_rt::app::{info_command, GpuOptions};

/// The report's value for `label` (`  label: yes`), or a panic naming it.
fn value<'a>(report: &'a str, label: &str) -> &'a str {
    report
        .lines()
        .find_map(|l| l.trim().strip_prefix(label)?.strip_prefix(": "))
        .unwrap_or_else(|| panic!("report lacks '{label}':\n{report}"))
}

fn yn(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

#[test]
fn validated_device_and_capability_report() {
    let ctx = common::validated_context();
    let caps = &ctx.caps;
    assert!(caps.api_version >= ash::vk::API_VERSION_1_3);
    assert!(caps.unusable.is_none());
    let report = caps.report();
    // The labels carry the queried values, and the context enabled exactly
    // what the device offers (ray tracing not switched off).
    assert_eq!(value(&report, "acceleration structures"), yn(caps.acceleration_structure), "{report}");
    assert_eq!(value(&report, "ray query"), yn(caps.ray_query), "{report}");
    assert_eq!(value(&report, "ray-tracing pipeline"), yn(caps.ray_tracing_pipeline), "{report}");
    assert_eq!(value(&report, "timestamps").split(' ').next(), Some(yn(caps.timestamps)), "{report}");
    assert!(value(&report, "Vulkan API").starts_with("1."), "{report}");
    assert_eq!(ctx.rt.acceleration_structure, caps.acceleration_structure);
    assert_eq!(ctx.rt.ray_query, caps.ray_query);
    assert_eq!(ctx.rt.ray_tracing_pipeline, caps.ray_tracing_pipeline);
    assert_eq!(ctx.accel.is_some(), caps.acceleration_structure);
    assert_eq!(ctx.rt_pipeline.is_some(), caps.ray_tracing_pipeline);
    // CI's Mesa 25 lavapipe has all three (README, support table).
    assert!(caps.acceleration_structure && caps.ray_query && caps.ray_tracing_pipeline, "{report}");
}

#[test]
fn info_lists_the_selected_device() {
    let s = info_command(&GpuOptions { validation: true, ..Default::default() }).unwrap();
    assert!(s.contains("(selected)"), "{s}");
    // The selected device's block carries the same values as its context.
    let ctx = common::validated_context();
    let block = s
        .split("device ")
        .find(|b| b.contains("(selected)"))
        .unwrap_or_else(|| panic!("no selected block:\n{s}"));
    assert_eq!(value(block, "ray query"), yn(ctx.caps.ray_query), "{s}");
    assert_eq!(value(block, "ray-tracing pipeline"), yn(ctx.caps.ray_tracing_pipeline), "{s}");
}

#[test]
fn ray_tracing_can_be_switched_off() {
    let ctx = common::validated(
        GpuOptions { validation: true, disable_ray_tracing: true, ..Default::default() }.context().unwrap(),
    );
    assert!(!ctx.rt.acceleration_structure && !ctx.rt.ray_query && !ctx.rt.ray_tracing_pipeline);
    assert!(ctx.accel.is_none() && ctx.rt_pipeline.is_none());
}

/// A leaked object is reported by vkDestroyDevice: the counters outlive the
/// context, so the error is seen after the drop (before it, all is clean).
#[test]
fn an_object_leaked_at_teardown_is_a_validation_error() {
    let _ = env_logger::builder().is_test(true).try_init();
    let ctx = GpuOptions { validation: true, ..Default::default() }.context().unwrap();
    let counters = ctx.validation_counters();
    let info = ash::vk::SamplerCreateInfo::default();
    // Deliberately never destroyed.
    let _sampler = unsafe { ctx.device.create_sampler(&info, None) }.unwrap();
    assert_eq!(counters.errors(), 0, "clean before teardown");
    drop(ctx);
    assert!(counters.errors() > 0, "the leaked VkSampler was not counted as a validation error");

    // A context that leaks nothing stays at 0 through teardown.
    let ctx = GpuOptions { validation: true, ..Default::default() }.context().unwrap();
    let counters = ctx.validation_counters();
    drop(ctx);
    assert_eq!(counters.errors(), 0, "clean context reported errors at teardown");
}
