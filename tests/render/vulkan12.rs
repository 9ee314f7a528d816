//! The Vulkan 1.2 path: RenderDoc 1.24 (Debian 12) shows lavapipe as a 1.2
//! device, so the renderer must run with the 1.3 features it uses taken from
//! their extensions. `--vulkan-api 1.2` (`max_api_version`) creates a 1.2
//! instance, which makes the validation layer check every call against 1.2:
//! a 1.3 structure or entry point used on that path is a validation error.
use crate::common;

use ash::vk;
use hybrid_rt::app::GpuOptions;
use hybrid_rt::render::shading::Mode;
use hybrid_rt::render::{RenderSettings, Renderer};
use hybrid_rt::vk::FeaturePath;

fn context(api: u32) -> common::ValidatedContext {
    let _ = env_logger::builder().is_test(true).try_init();
    common::validated(
        GpuOptions { validation: true, max_api_version: Some(api), ..Default::default() }
            .context()
            .expect("create a validated Vulkan context"),
    )
}

#[test]
fn a_1_2_device_takes_the_extension_path() {
    let ctx = context(vk::API_VERSION_1_2);
    let caps = &ctx.caps;
    assert_eq!(caps.used_api_version, vk::API_VERSION_1_2.min(caps.api_version));
    let Some(FeaturePath::Extensions12(exts)) = &caps.feature_path else {
        panic!("expected the 1.2 extension path, got {:?}", caps.feature_path);
    };
    for (name, _) in hybrid_rt::vk::features::REQUIRED_1_2 {
        assert!(exts.contains(name), "{name:?} not enabled: {exts:?}");
    }
    assert!(
        caps.report().contains("1.3 features: Vulkan 1.2 + extensions VK_KHR_synchronization2, "),
        "{}",
        caps.report()
    );
    // The 1.3 entry points the renderer calls are the extensions' (a layer
    // gives each name its own entry point, so the two are told apart), not
    // the core ones a 1.2 device need not have.
    let gdpa = ctx.instance.raw.fp_v1_0().get_device_proc_addr;
    let lookup = |name: &std::ffi::CStr| {
        unsafe { gdpa(ctx.device.handle(), name.as_ptr()) }.map(|f| f as usize).unwrap_or(0)
    };
    let fp = ctx.device.fp_v1_3();
    for (loaded, core, ext) in [
        (fp.cmd_pipeline_barrier2 as usize, c"vkCmdPipelineBarrier2", c"vkCmdPipelineBarrier2KHR"),
        (fp.queue_submit2 as usize, c"vkQueueSubmit2", c"vkQueueSubmit2KHR"),
        (fp.cmd_write_timestamp2 as usize, c"vkCmdWriteTimestamp2", c"vkCmdWriteTimestamp2KHR"),
        (fp.cmd_begin_rendering as usize, c"vkCmdBeginRendering", c"vkCmdBeginRenderingKHR"),
        (fp.cmd_end_rendering as usize, c"vkCmdEndRendering", c"vkCmdEndRenderingKHR"),
        (fp.cmd_set_cull_mode as usize, c"vkCmdSetCullMode", c"vkCmdSetCullModeEXT"),
    ] {
        assert_eq!(loaded, lookup(ext), "{core:?} is not loaded as {ext:?}");
        assert_ne!(loaded, lookup(core), "{core:?}: the core entry point on a 1.2 device");
    }
    // Ray tracing is independent of the path: lavapipe offers it on 1.2 too.
    assert!(caps.ray_query && caps.ray_tracing_pipeline, "{}", caps.report());

    let ctx13 = context(vk::API_VERSION_1_3);
    assert_eq!(ctx13.caps.feature_path, Some(FeaturePath::Core13));
}

/// The default scene (shadows, mirrors, glass: every pass) on every backend
/// and in both modes renders the same bytes through the 1.2 path as through
/// 1.3, validation clean (barriers, submits, timestamps, dynamic rendering
/// and cull mode all go through the extension entry points).
#[test]
fn the_1_2_path_renders_the_1_3_image_on_every_backend() {
    let scene = hybrid_rt::scene::Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    let extent = vk::Extent2D { width: 64, height: 36 };
    for (backend, mode) in
        common::BACKENDS.map(|b| (b, Mode::Hybrid)).into_iter().chain([(common::BACKENDS[0], Mode::Rt)])
    {
        let settings = RenderSettings { backend, mode, ..Default::default() };
        let frames: Vec<_> = [vk::API_VERSION_1_3, vk::API_VERSION_1_2]
            .into_iter()
            .map(|api| {
                let ctx = context(api);
                let mut r = Renderer::new(&ctx, &scene, extent).unwrap();
                let frame = r.render(&ctx, &scene, &scene.cameras[0], &settings).unwrap();
                assert_eq!(r.shading_config().unwrap().backend, Some(backend));
                assert!(frame.timings.iter().all(|(_, ms)| ms.is_finite()), "{:?}", frame.timings);
                r.destroy(&ctx);
                frame
            })
            .collect();
        let (max, share) = hybrid_rt::image_diff::diff_stats(&frames[0].ldr, &frames[1].ldr, 4, 0);
        eprintln!(
            "{backend:?} {mode:?}: 1.2 vs 1.3: max difference {max}/255 on {:.3}% of pixels",
            share * 100.0
        );
        assert_eq!(max, 0, "{backend:?} {mode:?}: the 1.2 path renders a different image");
    }
}
