//! Radiance at the edges of the number formats: environment texels near the
//! RGBE maximum and beyond half's range, emission beyond the G-buffer's
//! half-float range. Frames stay finite and both modes agree.
use crate::common;

use common::toml::*;

use std::path::PathBuf;

use hybrid_rt::render::shading::Mode;
use hybrid_rt::render::RenderSettings;

const W: u32 = 96;
const H: u32 = 54;

/// Writes a `w` x `h` grey Radiance .hdr whose texel (x, y) is `f(x, y)`.
fn hdr_map(name: &str, w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> PathBuf {
    common::write_hdr(name, w, h, |x, y| [f(x, y); 3])
}

fn sky_scene(map: &std::path::Path) -> String {
    scene_toml([
        environment_hdr(map.display()),
        camera([0.0, 1.0, 4.0], [0.0, 1.5, 0.0]).yfov(60),
        no_light(),
        lambert("ground", [0.5, 0.5, 0.5]),
        plane("ground", [40.0, 40.0]).material("ground"),
    ])
}

/// Texels of 1.7e38 (near the RGBE maximum): their sin-weighted sum
/// overflowed f32, the mean radiance became Inf, the ambient term NaN and
/// the frame black. Now the mean is summed in f64 and the frame is finite,
/// sky and ground alike lit.
#[test]
fn environment_texels_near_the_rgbe_maximum_keep_the_frame_finite() {
    let map = hdr_map("env_rgbe_max", 16, 8, |x, _| if x == 3 { 1.7e38 } else { 0.25 });
    let scene = common::scene_from_toml("env_rgbe_max", &sky_scene(&map));
    let frame = common::render_scene(&scene, W, H, &RenderSettings::default()); // asserts finite
    let lit = frame.ldr.chunks_exact(4).filter(|p| p[0] > 16).count();
    assert!(lit as f64 > 0.95 * (W * H) as f64, "only {lit} of {} pixels lit", W * H);
}

/// A sky of 1e5 (a sun's order of magnitude) is beyond half's 65504: the map
/// goes up as RGBA32F and the background shows 1e5, not 65504.
#[test]
fn environment_beyond_half_range_is_not_clamped() {
    let map = hdr_map("env_1e5", 16, 8, |_, _| 1e5);
    let scene = common::scene_from_toml("env_1e5", &sky_scene(&map));
    let frame = common::render_scene(&scene, W, H, &RenderSettings::default());
    // The top row sees only sky.
    for x in 0..W {
        let l = frame.radiance(x, 0)[0];
        assert!((l / 1e5 - 1.0).abs() < 0.01, "sky radiance {l} at ({x}, 0), expected 1e5");
    }
}

/// Emission of 1e6 would overflow the RGBA16F emissive G-buffer target (Inf)
/// while its reflection (read from the material buffer) saw 1e6: it is
/// clamped to 65504 for every hit, so hybrid and pure RT agree and the
/// frame is finite.
#[test]
fn emission_beyond_half_range_is_clamped_alike_in_both_modes() {
    let scene = common::scene_from_toml(
        "emissive_1e6",
        &scene_toml([
            black_sky(),
            camera([0.0, 1.0, 4.0], [0.0, 0.5, 0.0]).yfov(60),
            no_light(),
            emitter("blinding", [1e6, 1e6, 1e6]),
            mirror("mirror", [0.9, 0.9, 0.9]),
            cube("lamp", 0.6).at([0.0, 1.0, 0.0]).material("blinding"),
            plane("floor", [20.0, 20.0]).material("mirror"),
        ]),
    );
    let hybrid = common::render_scene(&scene, W, H, &RenderSettings::default());
    let rt = common::render_scene(&scene, W, H, &RenderSettings { mode: Mode::Rt, ..Default::default() });
    let max = hybrid.hdr.iter().fold(0.0f32, |m, v| m.max(*v));
    assert_eq!(max, hybrid_rt::gpu::material::MAX_EMISSIVE, "the lamp's radiance");
    let (worst, _) = hybrid_rt::image_diff::diff_stats(&hybrid.ldr, &rt.ldr, 4, 1);
    assert!(worst <= 1, "hybrid and pure RT differ by {worst}/255 on a 1e6 emitter");
    let rel =
        hybrid.hdr.iter().zip(&rt.hdr).map(|(a, b)| (a - b).abs() / a.abs().max(1.0)).fold(0.0f32, f32::max);
    assert!(rel < 1e-3, "HDR differs between modes by {rel} (relative)");
}
