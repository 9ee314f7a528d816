//! Anti-aliasing after tone mapping (`--aa edge|fxaa`): only edge pixels
//! change, and the filtered frame is closer (ꟻLIP) to a 4x4 supersampled
//! reference than the unfiltered one, on a scene of long straight edges
//! (assets/aa_edges.toml), in hybrid mode and in pure-RT mode on every
//! backend (pure RT has no depth attachment: the edge filter takes depth
//! from the primary hit in both modes).
use crate::common;

use hybrid_rt::render::shading::{AaMode, Backend, Mode};
use hybrid_rt::render::supersample::{render_supersampled, SampleFilter, Supersample};
use hybrid_rt::render::{AmbientMode, DebugView, FrameOutput, RenderSettings, Renderer};
use hybrid_rt::report::metrics::{flip, LdrImage};
use hybrid_rt::scene::Scene;
use hybrid_rt::vk::Context;

use common::BACKENDS;

const W: u32 = 96;
const H: u32 = 54;

fn scene() -> Scene {
    Scene::load(&common::repo_path("assets/aa_edges.toml")).unwrap()
}

fn ldr(f: &FrameOutput) -> LdrImage {
    LdrImage { width: f.width, height: f.height, rgb: f.rgb8().into_raw() }
}

fn render(ctx: &Context, r: &mut Renderer, scene: &Scene, s: &RenderSettings) -> FrameOutput {
    let out = r.render(ctx, scene, &scene.cameras[0], s).unwrap();
    assert!(out.all_finite(), "NaN or Inf reached the frame");
    out
}

fn reference(ctx: &Context, scene: &Scene, s: &RenderSettings) -> FrameOutput {
    let ss = Supersample { factor: 4, filter: SampleFilter::Box };
    let extent = ash::vk::Extent2D { width: W, height: H };
    render_supersampled(ctx, scene, &scene.cameras[0], extent, s, &ss).unwrap()
}

/// Pixels away from depth and normal discontinuities, from the G-buffer
/// debug views (which are never anti-aliased): every pixel of the 3x3
/// window the filter reads shows the centre's object and, within 3/255
/// per channel, its normal (so smooth curvature is "flat", a crease or a
/// silhouette is not). An independent definition: the shader's own edge
/// measure is not used.
fn flat_pixels(object: &FrameOutput, normal: &FrameOutput) -> Vec<bool> {
    let (w, h) = (object.width as i64, object.height as i64);
    let px = |f: &FrameOutput, x: i64, y: i64| {
        let i = ((y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) * 4) as usize;
        [f.ldr[i], f.ldr[i + 1], f.ldr[i + 2]]
    };
    let mut flat = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (o, n) = (px(object, x, y), px(normal, x, y));
            let same = (-1..=1).all(|dy| {
                (-1..=1).all(|dx| {
                    let (oq, nq) = (px(object, x + dx, y + dy), px(normal, x + dx, y + dy));
                    oq == o && nq.iter().zip(n).all(|(a, b)| a.abs_diff(b) <= 3)
                })
            });
            flat.push(same);
        }
    }
    flat
}

/// Asserts that `filtered` equals `plain` bit for bit on every `flat`
/// pixel and changed some others; returns the share of pixels changed.
fn assert_only_edges_change(what: &str, plain: &FrameOutput, filtered: &FrameOutput, flat: &[bool]) -> f64 {
    let n = flat.len();
    let flat_count = flat.iter().filter(|f| **f).count();
    // The scene is mostly flat: a mask of nothing would prove nothing.
    assert!(flat_count * 2 > n, "{what}: only {flat_count} of {n} pixels are flat");
    let (mut changed, mut changed_flat, mut first) = (0, 0, None);
    for (i, &is_flat) in flat.iter().enumerate() {
        if plain.ldr[i * 4..i * 4 + 4] != filtered.ldr[i * 4..i * 4 + 4] {
            changed += 1;
            if is_flat {
                changed_flat += 1;
                first = first.or(Some((i as u32 % plain.width, i as u32 / plain.width)));
            }
        }
    }
    assert_eq!(changed_flat, 0, "{what}: {changed_flat} flat pixels changed, the first at {first:?}");
    let share = changed as f64 / n as f64;
    assert!(share > 0.01, "{what}: only {changed} pixels changed: the filter did nothing");
    share
}

/// ꟻLIP of the unfiltered and the filtered frame against the reference;
/// asserts the filter lowered it.
fn assert_flip_lowered(
    what: &str,
    reference: &FrameOutput,
    plain: &FrameOutput,
    filtered: &FrameOutput,
) -> (f64, f64) {
    let r = ldr(reference);
    let before = flip(&r, &ldr(plain)).unwrap().mean();
    let after = flip(&r, &ldr(filtered)).unwrap().mean();
    eprintln!("{what}: ꟻLIP against 4x4 supersampled {before:.5} -> {after:.5}");
    assert!(after < before, "{what}: ꟻLIP {before:.5} without AA, {after:.5} with: not lowered");
    (before, after)
}

#[test]
fn edge_filter_changes_only_edges_and_lowers_flip_in_both_modes_on_every_backend() {
    let ctx = common::validated_context();
    let scene = scene();
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let mut hybrid_edge: Option<FrameOutput> = None;
    let cases = [(Mode::Hybrid, Backend::Auto)].into_iter().chain(BACKENDS.map(|b| (Mode::Rt, b)));
    for (mode, backend) in cases {
        let what = format!("{mode:?} {backend:?}");
        let base = RenderSettings { mode, backend, ..Default::default() };
        assert_eq!(base.aa, AaMode::Edge, "edge AA is the default");
        let plain = render(&ctx, &mut r, &scene, &RenderSettings { aa: AaMode::None, ..base });
        let edge = render(&ctx, &mut r, &scene, &base);
        assert!(r.pass_names().contains(&"edge aa"), "{what}: {:?}", r.pass_names());
        let object = render(&ctx, &mut r, &scene, &RenderSettings { debug_view: DebugView::Object, ..base });
        let normal = render(&ctx, &mut r, &scene, &RenderSettings { debug_view: DebugView::Normal, ..base });
        let flat = flat_pixels(&object, &normal);
        let share = assert_only_edges_change(&what, &plain, &edge, &flat);
        eprintln!("{what}: {:.1}% of pixels changed", share * 100.0);
        let reference = reference(&ctx, &scene, &base);
        assert_flip_lowered(&format!("{what} edge"), &reference, &plain, &edge);
        // Both modes measure depth from the primary hit: the same edges.
        match &hybrid_edge {
            None => hybrid_edge = Some(edge),
            Some(h) => {
                let (max, share) = hybrid_rt::image_diff::diff_stats(&h.ldr, &edge.ldr, 4, 1);
                assert!(
                    max <= 2 && share <= 0.002,
                    "{what} vs hybrid: max {max}, {:.3}% > 1/255",
                    share * 100.0
                );
            }
        }
    }
    r.destroy(&ctx);
}

#[test]
fn fxaa_changes_only_contrast_edges_and_lowers_flip() {
    let ctx = common::validated_context();
    let scene = scene();
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    // The SH ambient: the traced one's residual noise leaves few pixels whose 3x3 window is one colour.
    let base = RenderSettings { aa: AaMode::Fxaa, ambient: AmbientMode::Sh, ..Default::default() };
    let plain = render(&ctx, &mut r, &scene, &RenderSettings { aa: AaMode::None, ..base });
    let fxaa = render(&ctx, &mut r, &scene, &base);
    assert!(r.pass_names().contains(&"fxaa") && !r.pass_names().contains(&"edge aa"), "{:?}", r.pass_names());
    // FXAA sees luma, not geometry: a pixel whose 3x3 window is one colour
    // has no contrast and must not change.
    let (w, h) = (W as i64, H as i64);
    let at = |x: i64, y: i64| {
        let i = ((y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) * 4) as usize;
        &plain.ldr[i..i + 3]
    };
    let uniform: Vec<bool> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| (-1..=1).all(|dy| (-1..=1).all(|dx| at(x + dx, y + dy) == at(x, y))))
        .collect();
    let share = assert_only_edges_change("fxaa", &plain, &fxaa, &uniform);
    eprintln!("fxaa: {:.1}% of pixels changed", share * 100.0);
    let reference = reference(&ctx, &scene, &base);
    assert_flip_lowered("fxaa", &reference, &plain, &fxaa);
    r.destroy(&ctx);
}

#[test]
fn debug_views_and_aa_none_leave_the_tone_mapped_frame_as_it_is() {
    let ctx = common::validated_context();
    let scene = scene();
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let normal = RenderSettings { debug_view: DebugView::Normal, ..Default::default() };
    let with_edge = render(&ctx, &mut r, &scene, &normal);
    assert!(!r.pass_names().iter().any(|p| p.contains("aa")), "{:?}", r.pass_names());
    let with_none = render(&ctx, &mut r, &scene, &RenderSettings { aa: AaMode::None, ..normal });
    assert_eq!(with_edge.ldr, with_none.ldr, "a debug view is shown unfiltered");
    render(&ctx, &mut r, &scene, &RenderSettings { aa: AaMode::None, ..Default::default() });
    assert_eq!(r.pass_names().last(), Some(&"tonemap"), "--aa none ends with tone mapping");
    r.destroy(&ctx);
}

/// The edge filter shares its pixels' depths, normals and triangle exits
/// within 8x8 tiles, the border ones computed by whichever pixel of the
/// tile's border faces them (glsl/aa_edge.comp): the image must be that of
/// the per-pixel version, which computes everything itself. Frame sizes
/// that are not multiples of 8 leave partial tiles at the right and bottom.
#[test]
fn tiled_edge_filter_matches_the_per_pixel_one() {
    let ctx = common::validated_context();
    let scenes =
        [("aa_edges", scene()), ("default", Scene::load(&common::repo_path("assets/default.toml")).unwrap())];
    for (name, scene) in &scenes {
        for (w, h, mode) in [(101, 59, Mode::Hybrid), (64, 40, Mode::Rt)] {
            let mut r = Renderer::new(&ctx, scene, ash::vk::Extent2D { width: w, height: h }).unwrap();
            let tiled = RenderSettings { mode, ..Default::default() };
            let a = render(&ctx, &mut r, scene, &tiled);
            let tiled_config = r.shading_config().unwrap().edge_aa_tiled;
            let b = render(&ctx, &mut r, scene, &RenderSettings { edge_aa_tiled: false, ..tiled });
            // The two images are the same by design: only the frames'
            // configuration tells the per-pixel run from a second tiled one.
            assert!(
                tiled_config && !r.shading_config().unwrap().edge_aa_tiled,
                "{name}: edge_aa_tiled did not reach the frame's configuration"
            );
            let plain = render(&ctx, &mut r, scene, &RenderSettings { aa: AaMode::None, ..tiled });
            r.destroy(&ctx);
            let (_, filtered_tiled) = hybrid_rt::image_diff::diff_stats(&plain.ldr, &a.ldr, 4, 0);
            let (_, filtered) = hybrid_rt::image_diff::diff_stats(&plain.ldr, &b.ldr, 4, 0);
            let (max, share) = hybrid_rt::image_diff::diff_stats(&a.ldr, &b.ldr, 4, 0);
            eprintln!(
                "{name} {w}x{h} {mode:?}: {:.1}% (tiled) and {:.1}% (per-pixel) of pixels filtered; \
                 tiled vs per-pixel: max {max}/255 on {:.3}%",
                filtered_tiled * 100.0,
                filtered * 100.0,
                share * 100.0
            );
            // Without filtered pixels the comparison would prove nothing:
            // each path must change the frame against `--aa none` (a filter
            // that does nothing, or is skipped, leaves both equal to it).
            for (path, f) in [("tiled", filtered_tiled), ("per-pixel", filtered)] {
                assert!(
                    f > 0.01,
                    "{name} {w}x{h} {mode:?}: the {path} filter changed only {:.3}% of pixels against aa none",
                    f * 100.0
                );
            }
            // The same arithmetic, compiled twice: at most a rounding apart.
            assert!(
                max <= 1 && share <= 0.001,
                "{name} {w}x{h} {mode:?}: tiled differs, max {max}/255 on {share}"
            );
        }
    }
}
