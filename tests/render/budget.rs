//! The per-object ray-tracing budget (render/budget): in paper and effects
//! mode a budget of 0 with the paper's fallback (`--fallback none`) renders
//! exactly the raster-only image and an unlimited one exactly the full
//! hybrid image, on every backend; each effect's selection bit gates
//! exactly that effect; a partial effect traces its share of an object's
//! pixels on an ordered-dither lattice that nests as the share grows, and
//! the rest of the share is filled from it; a K = 0 object is never
//! selected; stickiness keeps the selection steady over a slow pan.
use crate::common;

use common::toml::*;
use common::BACKENDS;
use glam::Vec3;
use hybrid_rt::gpu::shared::{
    EFFECT_ALL, EFFECT_BIT_REFLECTIONS, EFFECT_BIT_REFRACTIONS, EFFECT_BIT_SHADOWS,
};
use hybrid_rt::image_diff::diff_stats;
use hybrid_rt::render::budget::effects::{selection_word, traced_fraction};
use hybrid_rt::render::budget::{BudgetMode, BudgetSettings, Fallback};
use hybrid_rt::render::shading::{AaMode, Effects};
use hybrid_rt::render::{AmbientMode, RenderSettings, Renderer};
use hybrid_rt::scene::{Camera, Scene};

const W: u32 = 96;
const H: u32 = 54;

fn budget(t: f64, stickiness: f32) -> Option<BudgetSettings> {
    Some(BudgetSettings { stickiness, ..BudgetSettings::paper(t) })
}

fn default_scene() -> Scene {
    Scene::load(&common::repo_path("assets/default.toml")).unwrap()
}

#[test]
fn zero_budget_is_raster_only_and_unlimited_is_full_hybrid_on_every_backend() {
    let scene = default_scene();
    for backend in BACKENDS {
        // Under a budget the ambient is SH (AmbientMode::pick): so are the frames it is compared with.
        let full = RenderSettings { backend, ambient: AmbientMode::Sh, ..Default::default() };
        let none = Effects { shadows: false, reflections: false, refractions: false, ..full.effects };
        let raster = common::render_scene(&scene, W, H, &RenderSettings { effects: none, ..full });
        let hybrid = common::render_scene(&scene, W, H, &full);
        // The scene's effects are visible: the two references differ.
        let (max_effects, share) = diff_stats(&raster.rgb8(), &hybrid.rgb8(), 3, 8);
        assert!(share > 0.02, "{backend:?}: the effects barely show ({:.2}%)", share * 100.0);
        for mode in [BudgetMode::Paper, BudgetMode::Effects] {
            let with = |t: f64| RenderSettings {
                budget: Some(BudgetSettings { mode, budget: t, stickiness: 0.0, fallback: Fallback::None }),
                ..full
            };
            let zero = common::render_scene(&scene, W, H, &with(0.0));
            let inf = common::render_scene(&scene, W, H, &with(f64::INFINITY));
            let (max_zero, _) = diff_stats(&raster.rgb8(), &zero.rgb8(), 3, 0);
            let (max_inf, _) = diff_stats(&hybrid.rgb8(), &inf.rgb8(), 3, 0);
            eprintln!(
                "{backend:?} {mode:?}: budget 0 vs raster only max {max_zero}, inf vs hybrid max {max_inf}; \
                 effects change {:.1}% of pixels (max {max_effects})",
                share * 100.0
            );
            assert_eq!(max_zero, 0, "{backend:?} {mode:?}: budget 0 differs from the raster-only image");
            assert_eq!(
                max_inf, 0,
                "{backend:?} {mode:?}: an unlimited budget differs from the full hybrid image"
            );
        }
    }
}

/// Each effect's bit gates exactly that effect: with only effect e on, a
/// selection of e alone renders the traced image and a selection of every
/// other bit the untraced one, bit for bit. (Effects are checked one at a
/// time: a traced chain keeps everything beyond its first ray, its own
/// shadow rays and nested reflections included, which global switches turn
/// off, so "all but e" has no global-switch equivalent.)
#[test]
fn each_effect_bit_gates_exactly_its_effect() {
    let scene = default_scene();
    let ctx = common::validated_context();
    let n = scene.objects.len();
    let camera = scene.cameras[0].clone();
    let b = BudgetSettings { fallback: Fallback::None, ..BudgetSettings::effects(f64::INFINITY) };
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let none = Effects { shadows: false, reflections: false, refractions: false, ..Effects::default() };
    // Under a budget the ambient is SH (AmbientMode::pick): so are the frames it is compared with.
    let with = |effects: Effects| RenderSettings { effects, ambient: AmbientMode::Sh, ..Default::default() };
    let untraced = r.render(&ctx, &scene, &camera, &with(none)).unwrap();
    let cases = [
        (EFFECT_BIT_SHADOWS, "shadows", Effects { shadows: true, ..none }),
        (EFFECT_BIT_REFLECTIONS, "reflections", Effects { reflections: true, ..none }),
        (EFFECT_BIT_REFRACTIONS, "refractions", Effects { refractions: true, ..none }),
    ];
    for (bit, name, only) in cases {
        let traced = r.render(&ctx, &scene, &camera, &with(only)).unwrap();
        let settings = RenderSettings { budget: Some(b), ..with(only) };
        let mut selected = |bits: u32| {
            // A frame under the budget first (its passes), then the override.
            r.render(&ctx, &scene, &camera, &settings).unwrap();
            r.set_budget_selection(&b, vec![bits; n]);
            r.render(&ctx, &scene, &camera, &settings).unwrap()
        };
        let (max_on, _) = diff_stats(&traced.rgb8(), &selected(1 << bit).rgb8(), 3, 0);
        let (max_off, _) = diff_stats(&untraced.rgb8(), &selected(EFFECT_ALL & !(1 << bit)).rgb8(), 3, 0);
        let (_, shows) = diff_stats(&untraced.rgb8(), &traced.rgb8(), 3, 4);
        eprintln!(
            "{name}: selected alone vs traced max {max_on}, every other bit vs untraced max {max_off}; \
             the effect shows on {:.1}% of pixels",
            shows * 100.0
        );
        assert!(shows > 0.005, "{name}: the default scene does not show the effect");
        assert_eq!(max_on, 0, "{name}: its bit alone does not render the traced effect");
        assert_eq!(max_off, 0, "{name}: the other bits render some of it");
    }
    r.destroy(&ctx);
}

/// The rank of a pixel in the 8x8 Bayer matrix (glsl/common/scene.glsl's
/// `budget_rank`, written out here from its definition: the bit-reversed
/// interleave of x ^ y and y).
fn bayer_rank(x: u32, y: u32) -> u32 {
    let (xy, y) = ((x ^ y) & 7, y & 7);
    let bit = |v: u32, b: u32| (v >> b) & 1;
    (bit(xy, 0) << 5)
        | (bit(y, 0) << 4)
        | (bit(xy, 1) << 3)
        | (bit(y, 1) << 2)
        | (bit(xy, 2) << 1)
        | bit(y, 2)
}

/// The default scene at 320x180 and a renderer whose selection the tests set
/// (`set_budget_selection`): paper mode's settings carry the override (its
/// report counts the rays of every frame, calibrated or not).
fn overridden(ctx: &hybrid_rt::vk::Context) -> (Scene, Camera, BudgetSettings, Renderer) {
    let scene = default_scene();
    let camera = scene.cameras[0].clone();
    let b = BudgetSettings { fallback: Fallback::None, ..BudgetSettings::paper(f64::INFINITY) };
    let r = Renderer::new(ctx, &scene, ash::vk::Extent2D { width: 320, height: 180 }).unwrap();
    (scene, camera, b, r)
}

/// A partial effect (effects mode's leftover budget) traces its share of an
/// object's pixels, so of its reflection rays, on the pixels whose ordered-
/// dither rank is below the word's count: the same pixels at every larger
/// share (a growing budget only adds), an even lattice at every share.
#[test]
fn a_partial_effect_traces_its_share_of_the_pixels_on_a_nested_lattice() {
    use hybrid_rt::render::DebugView;
    let ctx = common::validated_context();
    let (scene, camera, b, mut r) = overridden(&ctx);
    let n = scene.objects.len();
    let only_reflections =
        Effects { shadows: false, reflections: true, refractions: false, ..Effects::default() };
    let settings =
        RenderSettings { effects: only_reflections, budget: Some(b), aa: AaMode::None, ..Default::default() };
    let view = RenderSettings { debug_view: DebugView::Selection, ..settings };
    let mut reflection_rays = |word: u32| {
        r.render(&ctx, &scene, &camera, &settings).unwrap();
        r.set_budget_selection(&b, vec![word; n]);
        r.render(&ctx, &scene, &camera, &settings).unwrap();
        let rays = r.budget_report().unwrap().measured_rays[1];
        r.set_budget_selection(&b, vec![word; n]);
        let shown = r.render(&ctx, &scene, &camera, &view).unwrap().rgb8();
        (rays, shown)
    };
    let refl = 1 << EFFECT_BIT_REFLECTIONS;
    let (all_rays, _) = reflection_rays(refl);
    let (no_rays, _) = reflection_rays(0);
    assert!(all_rays > 2_000.0 && no_rays == 0.0, "reflection rays: all {all_rays}, none {no_rays}");
    let mut last: Option<image::RgbImage> = None;
    for ranks in [4u32, 16, 32, 48] {
        let share = ranks as f64 / 64.0;
        let word = selection_word(0, refl, share);
        assert_eq!(traced_fraction(word, EFFECT_BIT_REFLECTIONS as usize), share);
        let (rays, shown) = reflection_rays(word);
        let got = rays / all_rays;
        eprintln!("share {share}: {got:.3} of the reflection rays");
        assert!((got - share).abs() < 0.04, "share {share}: traced {got:.3} of the rays");
        // The selection view: green where reflections are traced, grey where not, nothing mixed.
        let traced = |img: &image::RgbImage, x, y| {
            let p = img.get_pixel(x, y);
            p[1] > p[0].saturating_add(20)
        };
        for (x, y, p) in shown.enumerate_pixels() {
            if p[0] == 0 && p[1] == 0 && p[2] == 0 {
                continue; // no primary hit
            }
            assert_eq!(traced(&shown, x, y), bayer_rank(x, y) < ranks, "share {share}: pixel ({x}, {y})");
            if let Some(prev) = &last {
                assert!(!traced(prev, x, y) || traced(&shown, x, y), "share {share} dropped ({x}, {y})");
            }
        }
        last = Some(shown);
    }
    r.destroy(&ctx);
}

/// A partial share reads as a lower-resolution effect, not as a pattern:
/// `composite` fills the untraced pixels of the share from the traced
/// lattice around them (common/budget_fill.glsl). Where reflections change
/// the image, a quarter share (and a sixteenth) must come far closer to
/// the fully traced image than the pixels it leaves to the fallback.
#[test]
fn a_partial_share_is_filled_from_the_traced_lattice() {
    let ctx = common::validated_context();
    let (scene, camera, b, mut r) = overridden(&ctx);
    let n = scene.objects.len();
    let settings = RenderSettings { budget: Some(b), aa: AaMode::None, ..Default::default() };
    let mut frame = |word: u32| {
        r.set_budget_selection(&b, vec![word; n]);
        r.render(&ctx, &scene, &camera, &settings).unwrap().rgb8()
    };
    let refl = 1 << EFFECT_BIT_REFLECTIONS;
    let rest = EFFECT_ALL & !refl;
    let full = frame(EFFECT_ALL);
    let untraced = frame(rest);
    let diff = |a: &image::Rgb<u8>, b: &image::Rgb<u8>| -> f64 {
        (0..3).map(|c| (a[c] as f64 - b[c] as f64).abs()).sum::<f64>() / 3.0
    };
    // The pixels reflections change.
    let changed: Vec<(u32, u32)> = full
        .enumerate_pixels()
        .filter(|(x, y, p)| diff(p, untraced.get_pixel(*x, *y)) > 4.0)
        .map(|(x, y, _)| (x, y))
        .collect();
    assert!(changed.len() > 1000, "{} pixels show reflections", changed.len());
    let error = |img: &image::RgbImage| -> f64 {
        changed.iter().map(|&(x, y)| diff(img.get_pixel(x, y), full.get_pixel(x, y))).sum::<f64>()
            / changed.len() as f64
    };
    let fallback = error(&untraced);
    for (ranks, bound) in [(16u32, 0.4), (4, 0.6)] {
        let img = frame(selection_word(rest, refl, ranks as f64 / 64.0));
        let e = error(&img);
        eprintln!("share {ranks}/64: mean error {e:.2} against {fallback:.2} untraced ({:.2})", e / fallback);
        assert!(e < bound * fallback, "share {ranks}/64: error {e:.2}, untraced {fallback:.2}");
    }
    r.destroy(&ctx);
}

/// Renders `frames` frames of `scene` from `cameras(i)` with one renderer
/// and returns each frame's selection (per object).
fn selections(
    scene: &Scene,
    settings: &RenderSettings,
    frames: usize,
    camera: impl Fn(usize) -> Camera,
) -> Vec<Vec<bool>> {
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let mut out = Vec::new();
    for i in 0..frames {
        r.render(&ctx, scene, &camera(i), settings).unwrap();
        out.push(r.budget_report().expect("a budget report").selection.mask.clone());
        let report = r.budget_report().unwrap();
        assert_eq!(report.effects.iter().map(|&b| b != 0).collect::<Vec<_>>(), report.selection.mask);
    }
    r.destroy(&ctx);
    drop(ctx);
    out
}

#[test]
fn an_object_of_relevance_zero_is_never_selected() {
    let mut scene = default_scene();
    let red = scene.objects.iter().position(|o| o.name == "red cube").expect("the default scene's red cube");
    scene.objects[red].props.relevance = 0.0;
    let cam = scene.cameras[0].clone();
    for b in [BudgetSettings::paper(f64::INFINITY), BudgetSettings::effects(f64::INFINITY)] {
        let settings = RenderSettings { budget: Some(b), ..Default::default() };
        let sel = selections(&scene, &settings, 2, |_| cam.clone());
        for mask in &sel {
            assert!(!mask[red], "{:?}: the K = 0 object was selected: {mask:?}", b.mode);
            assert!(
                mask.iter().filter(|&&m| m).count() >= 4,
                "an unlimited budget selects the rest: {mask:?}"
            );
        }
    }
}

/// Two equal mirror spheres side by side; the budget fits one. The camera
/// sways left and right across the midpoint: by centrality the selection
/// flips at every crossing, unless the selected sphere keeps its place.
fn two_spheres() -> String {
    scene_toml([
        camera([0.0, 0.0, 5.0], [0.0; 3]).yfov(50),
        directional([-0.3, -1.0, -0.4], 3.0),
        mirror("mirror", [0.9, 0.9, 0.9]).roughness(0.05),
        sphere("left", 0.5).at([-1.0, 0.0, 0.0]).material("mirror"),
        sphere("right", 0.5).at([1.0, 0.0, 0.0]).material("mirror"),
    ])
}

#[test]
fn stickiness_steadies_the_selection_over_a_slow_pan() {
    let scene = common::scene_from_toml("budget_two_spheres", &two_spheres());
    let base = scene.cameras[0].clone();
    // 40 frames swaying the view +-0.4 units, period 10 frames.
    let pan = |i: usize| {
        let x = 0.4 * (i as f32 * std::f32::consts::TAU / 10.0 + 0.3).sin();
        Camera::look_at("pan", base.position(), Vec3::new(x, 0.0, 0.0), base.yfov, base.znear)
    };
    let all = selections(
        &scene,
        &RenderSettings { budget: budget(f64::INFINITY, 0.0), ..Default::default() },
        1,
        pan,
    );
    assert!(all[0].iter().all(|&m| m), "both spheres visible: {all:?}");
    // Room for one sphere (their costs are about equal).
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let settings = RenderSettings { budget: budget(f64::INFINITY, 0.0), ..Default::default() };
    r.render(&ctx, &scene, &pan(0), &settings).unwrap();
    let t = 0.6 * r.budget_report().unwrap().selection.spent;
    r.destroy(&ctx);
    drop(ctx);
    let changes = |stickiness: f32| {
        let settings = RenderSettings { budget: budget(t, stickiness), ..Default::default() };
        let sel = selections(&scene, &settings, 40, pan);
        assert!(sel.iter().all(|m| m.iter().filter(|&&b| b).count() == 1), "one sphere fits: {sel:?}");
        sel.windows(2).filter(|w| w[0] != w[1]).count()
    };
    let (loose, sticky) = (changes(0.0), changes(1e4));
    eprintln!("budget {t:.0}: selection changes over the sway: I = 0: {loose}, I = 1e4: {sticky}");
    assert!(loose >= 4, "without stickiness the selection should follow the sway ({loose} changes)");
    assert!(sticky * 4 <= loose, "stickiness does not steady the selection: {sticky} vs {loose} changes");
}

/// `--debug-view selection` shows the selection the lit frame traces: a
/// debug view traces no rays, so its frames neither calibrate the cost
/// model nor teach it that rays are free (issue 41 item 3: with budget 10
/// the lit frame traced 0 of 5 objects and the view showed 5 of 5 red).
#[test]
fn the_selection_view_shows_what_the_lit_frame_traces() {
    use hybrid_rt::render::DebugView;
    let scene = default_scene();
    let cam = scene.cameras[0].clone();
    let extent = ash::vk::Extent2D { width: W, height: H };
    let ctx = common::validated_context();
    // 1 µs: far below what any ray costs, above what rays cost the model
    // when a debug view teaches it (nothing).
    for t in [1e-3, f64::INFINITY] {
        let b = BudgetSettings::effects(t);
        let view = RenderSettings { budget: Some(b), debug_view: DebugView::Selection, ..Default::default() };
        let mut r = Renderer::new(&ctx, &scene, extent).unwrap();
        let shown = r.render(&ctx, &scene, &cam, &view).unwrap();
        let report = r.budget_report().expect("a budget report").clone();
        r.destroy(&ctx);
        let visible = report.objects.iter().filter(|o| o.pixels > 0).count();
        let picked = report.selection.selected.len();
        eprintln!("budget {t} ms, selection view: {}", report.summary());
        assert!(visible >= 4, "{visible} visible objects");
        let Some(predicted) = report.predicted_ms else { panic!("effects mode predicts ms") };
        if t.is_finite() {
            assert_eq!(
                picked,
                0,
                "budget {t}: the view selects as if rays cost nothing: {}",
                report.summary()
            );
            assert!(predicted > 0.0, "the cost model learnt that rays are free: {}", report.summary());
            // The view itself: exactly the image of an empty selection.
            let mut r = Renderer::new(&ctx, &scene, extent).unwrap();
            r.set_budget_selection(&b, vec![0; scene.objects.len()]);
            let empty = r.render(&ctx, &scene, &cam, &view).unwrap();
            r.destroy(&ctx);
            let (max, _) = diff_stats(&empty.rgb8(), &shown.rgb8(), 3, 0);
            assert_eq!(max, 0, "budget {t}: the selection view shows objects selected");
        } else {
            assert_eq!(
                picked,
                visible,
                "an unlimited budget selects every visible object: {}",
                report.summary()
            );
        }
    }
}

/// The `heuristic` pass counts each object's covered pixels and their
/// bounds exactly: against the ObjectId view's per-pixel ids, read on the
/// host, at a size that leaves partial 8x8 tiles, on the default scene and
/// on Sponza with spheres (many objects sharing tiles); with the subgroup
/// reduction and with the shared-memory one (devices without subgroup
/// arithmetic).
#[test]
fn heuristic_counts_each_objects_pixels_and_bounds_exactly() {
    use hybrid_rt::app::GpuOptions;
    use hybrid_rt::render::DebugView;
    let (w, h) = (101, 59);
    let sponza = Scene::load(&common::repo_path("assets/sponza_spheres.toml")).unwrap();
    let scenes = [default_scene(), sponza];
    for subgroups in [true, false] {
        let opts =
            GpuOptions { validation: true, disable_subgroup_arithmetic: !subgroups, ..Default::default() };
        let ctx = common::validated(opts.context().unwrap());
        assert_eq!(ctx.caps.subgroup_arithmetic, subgroups, "lavapipe has subgroup arithmetic");
        for scene in &scenes {
            let cam = scene.cameras[0].clone();
            let mut r = Renderer::new(&ctx, scene, ash::vk::Extent2D { width: w, height: h }).unwrap();
            let plain = RenderSettings { aa: AaMode::None, ..Default::default() };
            let view = RenderSettings { debug_view: DebugView::ObjectId, ..plain };
            let ids = r.render(&ctx, scene, &cam, &view).unwrap();
            r.render(&ctx, scene, &cam, &RenderSettings { budget: budget(f64::INFINITY, 0.0), ..plain })
                .unwrap();
            let report = r.budget_report().expect("a budget report").clone();
            r.destroy(&ctx);
            // Per object: pixels, min x, min y, max x, max y.
            let mut want = vec![(0u32, [u32::MAX, u32::MAX, 0, 0]); scene.objects.len()];
            for (i, p) in ids.hdr.chunks_exact(4).enumerate() {
                let id = p[0].round() as usize;
                if id == 0 {
                    continue;
                }
                let (x, y) = (i as u32 % w, i as u32 / w);
                let (n, b) = &mut want[id - 1];
                *n += 1;
                *b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
            }
            let visible = want.iter().filter(|(n, _)| *n > 0).count();
            assert!(visible >= 4, "{visible} objects visible");
            for (o, (stats, (n, b))) in report.objects.iter().zip(&want).enumerate() {
                assert_eq!(stats.pixels, *n, "subgroups {subgroups}, object {o}: covered pixels");
                if *n > 0 {
                    let bounds = [b[0] as f32, b[1] as f32, b[2] as f32 + 1.0, b[3] as f32 + 1.0];
                    let got = [stats.bbox_min[0], stats.bbox_min[1], stats.bbox_max[0], stats.bbox_max[1]];
                    assert_eq!(got, bounds, "subgroups {subgroups}, object {o}: pixel bounds");
                }
            }
        }
        ctx.finish().unwrap();
    }
}
