//! Alpha cut-outs seen by reflection rays filter their alpha like the
//! rasterizer does: the reflection ray's cone picks the mip level of the
//! alpha test (glsl/common/hit.glsl, `g_alpha_cone`), not mip 0. A fine
//! stripe mask (70% opaque) seen far away in a mirror is then a solid
//! surface, as the raster shows it directly; testing mip 0 lets about 40% of
//! the pixels see the sky through the gaps, and the cut-out sparkles as the
//! camera moves.
use crate::common;

use common::toml::*;
use common::BACKENDS;
use hybrid_rt::render::RenderSettings;

/// A 100 x 100 quad in the XY plane, uv repeated 16 times, with an
/// alpha-masked base-colour texture of vertical stripes: 7 opaque red
/// texels, 3 transparent, across 256 texels.
fn fence_gltf() -> std::path::PathBuf {
    let (w, h) = (256u32, 256u32);
    let img = image::RgbaImage::from_fn(w, h, |x, _| {
        if x % 10 < 7 {
            image::Rgba([230, 20, 20, 255])
        } else {
            image::Rgba([230, 20, 20, 0])
        }
    });
    common::scenes::masked_quad_gltf("alpha_lod_fence.gltf", 50.0, 16.0, &img)
}

/// The camera looks at a mirror 5 units ahead that fills the view; the
/// fence stands 25 units behind the camera (facing it), so every pixel sees
/// the fence 35 or more units away by reflection: ~30 texels per pixel.
fn scene() -> hybrid_rt::scene::Scene {
    let fence = fence_gltf();
    let toml = scene_toml([
        environment([0.1, 0.3, 1.0]),
        camera([0.0; 3], [0.0, 0.0, -1.0]).yfov(60),
        directional([0.2, -1.0, -0.3], 3.0),
        mirror("mirror", [1.0; 3]),
        plane("mirror", [40.0, 40.0]).material("mirror").at([0.0, 0.0, -5.0]).rot([90.0, 0.0, 0.0]),
        gltf("fence", fence.display()).at([0.0, 0.0, 25.0]),
    ]);
    common::scene_from_toml("alpha_lod", &toml)
}

#[test]
fn cut_outs_seen_in_a_mirror_filter_their_alpha_by_the_ray_cone() {
    let scene = scene();
    let (w, h) = (96, 54);
    for backend in BACKENDS {
        let settings = RenderSettings { backend, ..Default::default() };
        let out = common::render_scene(&scene, w, h, &settings);
        let img = out.rgb8();
        let (mut sky, mut fence) = (0usize, 0usize);
        for p in img.pixels() {
            let [r, _, b] = p.0;
            if b > r {
                sky += 1;
            } else {
                fence += 1;
            }
        }
        let share = sky as f64 / (w * h) as f64;
        eprintln!(
            "{backend:?}: {:.2}% of the mirror shows the sky through the fence ({fence} fence)",
            share * 100.0
        );
        // Mip-0 alpha tests: ~40% (the stripes' gaps, seen failing).
        assert!(share < 0.02, "{backend:?}: {:.2}% of pixels see through the fence", share * 100.0);
    }
}

/// A 20 x 20 quad in the XY plane (uv once across it) with an alpha-masked
/// texture of 4 vertical stripes: 8 opaque red texels, 8 transparent, of 64;
/// `holes: false` makes the transparent texels opaque (the same red).
fn window_fence_gltf(holes: bool) -> std::path::PathBuf {
    let img = image::RgbaImage::from_fn(64, 64, |x, _| {
        let alpha = if holes && x % 16 >= 8 { 0 } else { 255 };
        image::Rgba([230, 20, 20, alpha])
    });
    let file = if holes { "alpha_window_fence.gltf" } else { "alpha_window_fence_opaque.gltf" };
    common::scenes::masked_quad_gltf(file, 10.0, 1.0, &img)
}

/// The camera looks at a mirror 3 units ahead that fills the view; 2 units
/// behind the camera the fence faces it, and 3 units behind the fence a
/// glowing green wall (black: the light adds nothing to it). Each reflection ray meets the fence ~8 units away,
/// where a pixel covers ~0.15 units and a stripe 2.5 (8 texels of 0.31):
/// the ray cone picks mip 0 or 1, where the gaps are still gaps.
fn window_scene(holes: bool) -> hybrid_rt::scene::Scene {
    let fence = window_fence_gltf(holes);
    let toml = scene_toml([
        environment([0.1, 0.3, 1.0]),
        camera([0.0; 3], [0.0, 0.0, -1.0]).yfov(60),
        // Lights the fence's side the mirror sees (through the mirror:
        // no shadows), so it is plainly red.
        directional([0.0, -0.2, 1.0], 3.0).no_shadows(),
        mirror("mirror", [1.0; 3]),
        emitter("wall", [0.1, 1.0, 0.2]),
        plane("mirror", [40.0, 40.0]).material("mirror").at([0.0, 0.0, -3.0]).rot([90.0, 0.0, 0.0]),
        gltf("fence", fence.display()).at([0.0, 0.0, 2.0]),
        plane("wall", [40.0, 40.0]).material("wall").at([0.0, 0.0, 5.0]).rot([-90.0, 0.0, 0.0]),
    ]);
    common::scene_from_toml(if holes { "alpha_window" } else { "alpha_window_opaque" }, &toml)
}

/// Shares of the frame showing the green wall and the red fence.
fn wall_and_fence(img: &image::RgbImage) -> (f64, f64) {
    let (mut wall, mut fence) = (0usize, 0usize);
    for p in img.pixels() {
        let [r, g, b] = p.0.map(i32::from);
        // Tone mapped, the wall is about (69, 199, 103); the lit fence is red.
        if g > r + 60 && g > b + 60 {
            wall += 1;
        } else if r > g + 20 && r > b + 20 {
            fence += 1;
        }
    }
    let n = (img.width() * img.height()) as f64;
    (wall as f64 / n, fence as f64 / n)
}

/// A reflection ray passes through a cut-out's gaps: the mirror shows the
/// wall behind the fence through them (half of the fence is gaps), on every
/// backend; with the gaps made opaque it shows none of it (so the wall seen
/// is the one behind the fence, not some other path to it).
#[test]
fn reflection_rays_see_through_the_gaps_of_a_near_cut_out() {
    let (w, h) = (96, 54);
    for backend in BACKENDS {
        let settings = RenderSettings { backend, ..Default::default() };
        let out = common::render_scene(&window_scene(true), w, h, &settings);
        let (wall, fence) = wall_and_fence(&out.rgb8());
        eprintln!("{backend:?}: the mirror shows {:.1}% wall, {:.1}% fence", wall * 100.0, fence * 100.0);
        // 50% of the fence is gaps (measured: 50.0% wall, 50.0% fence on
        // every backend); 10 points of room for the gaps' borders (the
        // cone's mip, the edge filter). An alpha test that ignores the mask
        // (or a fence opaque to reflection rays) shows no wall at all, a
        // mip too coarse narrows the gaps, one that ignores the fence shows
        // no fence.
        assert!(
            wall > 0.4,
            "{backend:?}: only {:.1}% of the mirror shows the wall through the fence's gaps",
            wall * 100.0
        );
        assert!(fence > 0.4, "{backend:?}: only {:.1}% of the mirror shows the fence", fence * 100.0);
    }
    let out = common::render_scene(&window_scene(false), w, h, &RenderSettings::default());
    let (wall, fence) = wall_and_fence(&out.rgb8());
    eprintln!("gaps opaque: the mirror shows {:.1}% wall, {:.1}% fence", wall * 100.0, fence * 100.0);
    assert!(
        wall == 0.0 && fence > 0.95,
        "gaps opaque: {:.1}% wall, {:.1}% fence",
        wall * 100.0,
        fence * 100.0
    );
}
