//! The frame architecture: which passes a frame records in each mode and
//! configuration, which targets it allocates, and that the barriers the
//! pass layer derives are clean under validation and synchronization
//! validation on every backend in both modes.
use crate::common;

use hybrid_rt::render::settings::PrimaryVisibility;
use hybrid_rt::render::shading::{AaMode, Backend, Mode};
use hybrid_rt::render::{AmbientMode, DebugView, RenderSettings, Renderer};
use hybrid_rt::scene::Scene;

use common::toml::*;
use common::BACKENDS;

/// A frame's recorded passes (with the timings' names) and allocated targets.
fn frame_of(
    ctx: &hybrid_rt::vk::Context,
    scene: &Scene,
    s: &RenderSettings,
) -> (Vec<&'static str>, Vec<&'static str>) {
    let mut r = Renderer::new(ctx, scene, ash::vk::Extent2D { width: 48, height: 27 }).unwrap();
    let out = r.render(ctx, scene, &scene.cameras[0], s).unwrap();
    assert!(out.all_finite());
    let passes = r.pass_names();
    // Every recorded pass is timed under its own name (plus the readback).
    let timed: Vec<_> = out.timings.iter().map(|(n, _)| *n).filter(|n| *n != "readback").collect();
    assert_eq!(timed, passes, "timestamps per recorded pass");
    let targets = r.targets().describe().into_iter().map(|(n, _)| n).collect();
    r.destroy(ctx);
    (passes, targets)
}

#[test]
fn every_backend_and_mode_records_the_stages_clean_under_sync_validation() {
    let ctx = common::sync_validated_context();
    let scene = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    for backend in BACKENDS {
        let hybrid = RenderSettings { backend, ..Default::default() };
        let (h, targets) = frame_of(&ctx, &scene, &hybrid);
        assert_eq!(
            h,
            [
                "gbuffer",
                "gbuffer resolve",
                "direct",
                "ao",
                "ao filter",
                "specular",
                "glossy",
                "glossy filter",
                "composite",
                "tonemap",
                "edge aa"
            ],
            "{backend:?} hybrid"
        );
        assert!(targets.contains(&"gbuffer depth (reversed-Z)"), "{targets:?}");
        // The compacted specular pass's list (render/passes/compacted.rs).
        assert!(targets.contains(&"work list"), "{targets:?}");
        let rt = RenderSettings { backend, mode: Mode::Rt, ..Default::default() };
        let (p, targets) = frame_of(&ctx, &scene, &rt);
        assert_eq!(
            p,
            [
                "primary",
                "direct",
                "ao",
                "ao filter",
                "specular",
                "glossy",
                "glossy filter",
                "composite",
                "tonemap",
                "edge aa"
            ],
            "{backend:?} rt"
        );
        // Pure RT differs only in how the primary hits are found (raster
        // visibility buffer + resolve vs camera rays), and needs no depth buffer.
        assert_eq!(h[2..], p[1..]);
        assert!(!targets.contains(&"gbuffer depth (reversed-Z)"), "{targets:?}");
        // Traced primary visibility: camera rays write the hit ids instead
        // of the raster pass and resolve them in the same pass (no
        // `gbuffer resolve`), and no depth buffer exists.
        let traced = RenderSettings { primary_visibility: PrimaryVisibility::Traced, ..hybrid };
        let (t, targets) = frame_of(&ctx, &scene, &traced);
        assert_eq!(t[0], "visibility trace", "{backend:?} traced");
        assert_eq!(t[1..], h[2..]);
        assert!(!targets.contains(&"gbuffer depth (reversed-Z)"), "{targets:?}");
    }
    // Under auto a frame records one technique: the first probe frame, the
    // raster and its resolve.
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: 48, height: 27 }).unwrap();
    r.choices.visibility.measure = true;
    let s = RenderSettings { backend: Backend::Compute, ..Default::default() };
    let out = r.render(&ctx, &scene, &scene.cameras[0], &s).unwrap();
    assert_eq!(r.pass_names()[..3], ["gbuffer", "gbuffer resolve", "direct"]);
    let ran: Vec<_> = out.timings.iter().map(|(n, _)| *n).collect();
    assert_eq!(ran[..3], r.pass_names()[..3], "{ran:?}");
    r.destroy(&ctx);
    common::assert_validation_clean(&ctx);
}

#[test]
fn passes_and_targets_a_scene_does_not_need_are_left_out() {
    let ctx = common::validated_context();
    // Rough, opaque materials and no shadow-casting light: nothing to trace.
    let plain = common::scene_from_toml(
        "frame_plain",
        &scene_toml([
            camera([0.0, 2.0, 5.0], [0.0; 3]),
            directional([0.0, -1.0, -0.3], 2.0).no_shadows(),
            clay().roughness(0.9),
            primitive("ball", "sphere").material("clay"),
            plane("floor", 10.0).at([0.0, -1.0, 0.0]).material("clay"),
        ]),
    );
    let sh = RenderSettings { ambient: AmbientMode::Sh, ..Default::default() };
    let (passes, targets) = frame_of(&ctx, &plain, &sh);
    assert_eq!(passes, ["gbuffer", "gbuffer resolve", "direct", "composite", "tonemap", "edge aa"]);
    assert!(!targets.contains(&"specular chain") && !targets.contains(&"work list"), "{targets:?}");
    // The ball hides part of the sky from the floor: the traced ambient (the default) has something to
    // trace; under a black sky with no light to bounce it has not.
    let (passes, targets) = frame_of(&ctx, &plain, &RenderSettings::default());
    let traced =
        ["gbuffer", "gbuffer resolve", "direct", "ao", "ao filter", "composite", "tonemap", "edge aa"];
    assert_eq!(passes, traced);
    assert!(
        targets.contains(&"ambient visibility") && targets.contains(&"ambient bounce sample"),
        "{targets:?}"
    );
    let dark = common::scene_from_toml(
        "frame_dark",
        &scene_toml([
            black_sky(),
            camera([0.0, 2.0, 5.0], [0.0; 3]),
            no_light(),
            clay().roughness(0.9),
            primitive("ball", "sphere").material("clay"),
            plane("floor", 10.0).at([0.0, -1.0, 0.0]).material("clay"),
        ]),
    );
    let (passes, _) = frame_of(&ctx, &dark, &RenderSettings::default());
    assert_eq!(passes, ["gbuffer", "gbuffer resolve", "direct", "composite", "tonemap", "edge aa"]);

    // Glossy but nothing mirrors or transmits: glossy reflections without the specular chain (and the
    // filter reads no chain); a mirror alone: the chain without the glossy passes.
    let one = |name: &str, roughness: f32| {
        common::scene_from_toml(
            name,
            &scene_toml([
                camera([0.0, 2.0, 5.0], [0.0; 3]),
                directional([0.0, -1.0, -0.3], 2.0).no_shadows(),
                material("metal").base([0.9, 0.8, 0.5]).metallic(1.0).roughness(roughness),
                primitive("ball", "sphere").material("metal"),
            ]),
        )
    };
    let (passes, targets) = frame_of(&ctx, &one("frame_glossy", 0.3), &RenderSettings::default());
    let glossy = [
        "gbuffer",
        "gbuffer resolve",
        "direct",
        "ao",
        "ao filter",
        "glossy",
        "glossy filter",
        "composite",
        "tonemap",
        "edge aa",
    ];
    assert_eq!(passes, glossy);
    assert!(!targets.contains(&"specular chain") && targets.contains(&"glossy sample"), "{targets:?}");
    // A one-sample frame (render, bench, report) blends no history: no `glossy temporal`, no history or
    // blend target; the viewer's temporal reuse brings them in before the filter.
    assert!(!targets.contains(&"glossy history") && !targets.contains(&"glossy blend"), "{targets:?}");
    let temporal = RenderSettings { glossy_temporal: true, ..Default::default() };
    let (passes, targets) = frame_of(&ctx, &one("frame_glossy_temporal", 0.3), &temporal);
    let mut with_history = glossy.to_vec();
    with_history.insert(6, "glossy temporal");
    assert_eq!(passes, with_history);
    assert!(targets.contains(&"glossy history") && targets.contains(&"glossy blend"), "{targets:?}");
    let (passes, targets) = frame_of(&ctx, &one("frame_mirror", 0.05), &RenderSettings::default());
    assert_eq!(
        passes,
        [
            "gbuffer",
            "gbuffer resolve",
            "direct",
            "ao",
            "ao filter",
            "specular",
            "composite",
            "tonemap",
            "edge aa"
        ]
    );
    assert!(
        !["glossy sample", "glossy history", "glossy blend", "reflected radiance"]
            .iter()
            .any(|t| targets.contains(t)),
        "{targets:?}"
    );

    // The default scene with reflections and refractions switched off.
    let scene = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    let mut s = RenderSettings { backend: Backend::Compute, ..Default::default() };
    s.effects.reflections = false;
    s.effects.refractions = false;
    let (passes, targets) = frame_of(&ctx, &scene, &s);
    assert_eq!(passes, traced);
    assert!(!targets.contains(&"specular chain") && !targets.contains(&"work list"), "{targets:?}");

    // --aa none: tone mapping's image is the result, no AA target; fxaa
    // instead of the edge filter.
    let none = RenderSettings { aa: AaMode::None, ..s };
    let (passes, targets) = frame_of(&ctx, &scene, &none);
    assert_eq!(passes, ["gbuffer", "gbuffer resolve", "direct", "ao", "ao filter", "composite", "tonemap"]);
    assert!(!targets.contains(&"anti-aliased output"), "{targets:?}");
    let (passes, _) = frame_of(&ctx, &scene, &RenderSettings { aa: AaMode::Fxaa, ..s });
    assert_eq!(
        passes,
        ["gbuffer", "gbuffer resolve", "direct", "ao", "ao filter", "composite", "tonemap", "fxaa"]
    );

    // A debug view shows the G-buffer: no light pass at all, and unfiltered.
    let debug = RenderSettings { debug_view: DebugView::Normal, ..Default::default() };
    let (passes, targets) = frame_of(&ctx, &scene, &debug);
    assert_eq!(passes, ["gbuffer", "gbuffer resolve", "composite", "tonemap"]);
    assert!(!targets.contains(&"anti-aliased output"), "{targets:?}");
    assert!(!targets.contains(&"direct light"), "{targets:?}");
    common::assert_validation_clean(&ctx);
}

/// The G-buffer is 24 bytes a pixel with the primary-hit target and the
/// depth buffer (albedo 4, octahedral normal 4, material 4, hit 8, depth 4;
/// no emission target), 20 in pure ray-traced mode (no depth buffer); and a
/// scene that needs no secondary effect allocates fewer targets in all.
#[test]
fn gbuffer_is_24_bytes_per_pixel_and_an_effect_free_frame_allocates_less() {
    use hybrid_rt::render::passes::gbuffer;
    let ctx = common::validated_context();
    let extent = ash::vk::Extent2D { width: 48, height: 27 };
    let frame = |scene: &Scene, s: &RenderSettings| {
        let mut r = Renderer::new(&ctx, scene, extent).unwrap();
        r.render(&ctx, scene, &scene.cameras[0], s).unwrap();
        let described = r.targets().describe();
        let bpp = gbuffer::bytes_per_pixel(r.targets());
        r.destroy(&ctx);
        (described, bpp)
    };
    let scene = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    let hybrid = RenderSettings { backend: Backend::Compute, ..Default::default() };
    let (targets, bpp) = frame(&scene, &hybrid);
    let names: Vec<_> = targets.iter().map(|(n, _)| *n).collect();
    // By name: the order is the order of first use.
    let mut gbuffer: Vec<_> = targets.iter().filter(|(n, _)| n.starts_with("gbuffer ")).copied().collect();
    gbuffer.sort();
    assert_eq!(
        gbuffer,
        [
            ("gbuffer albedo+occlusion", 4),
            ("gbuffer depth (reversed-Z)", 4),
            ("gbuffer hit (instance, primitive)", 8),
            ("gbuffer metallic+roughness+transmission", 4),
            ("gbuffer normal (octahedral)", 4),
        ],
        "{names:?}"
    );
    assert_eq!(bpp, 24);
    let (_, rt_bpp) = frame(&scene, &RenderSettings { mode: Mode::Rt, ..hybrid });
    assert_eq!(rt_bpp, 20, "pure RT: the same targets but the depth buffer");

    let mut plain = hybrid;
    plain.effects.shadows = false;
    plain.effects.reflections = false;
    plain.effects.refractions = false;
    let (plain_targets, plain_bpp) = frame(&scene, &plain);
    assert_eq!(plain_bpp, 24);
    let all = |t: &[(&str, u32)]| t.iter().map(|(_, b)| b).sum::<u32>();
    assert!(
        plain_targets.len() < targets.len() && all(&plain_targets) < all(&targets),
        "effect-free {plain_targets:?} vs {targets:?}"
    );
    common::assert_validation_clean(&ctx);
}
