//! KHR_materials_clearcoat (glsl/common/brdf.glsl `coat_weight` / `coat_layer`, split_sum.glsl
//! `coat_env_specular`, integrator.glsl's coat mirror branch, path/bsdf.glsl's coat lobe; the G-buffer
//! does not store it, gbuffer_read.glsl `primary_clearcoat` looks it up):
//!
//! - A smooth coat over a floor that reflects nothing itself (black, KHR_materials_specular weight 0)
//!   under a constant sky reads L c F(theta), F Schlick's from 0.04: per pixel on every backend and
//!   for the path tracer (its mean; pixels within its jitter), for c = 1 and 0.5.
//! - A rough coat (0.5) over the same floor, and over a grey diffuse one: the hybrid's split sum
//!   against the path tracer's sampled lobe, mean within 1 % of the sky.
//! - A glossy coat (0.3) over that floor reflects a sunlit wall standing on it as the path tracer
//!   does (the `glossy` pass samples the coat's lobe), within 5 %; without reflection rays it does not.
//! - Textures (R weight, G roughness) render as the factors they hold; the coat ignores the base's
//!   normal map and follows its own.
use crate::common;

use common::toml::*;
use hybrid_rt::render::shading::{Backend, Effects, Mode};
use hybrid_rt::render::{AmbientMode, FrameOutput, PathSettings, RenderSettings};
use hybrid_rt::scene::Scene;

const W: u32 = 64;
const H: u32 = 48;
const SKY: f32 = 2.0;

/// Every backend's hybrid frame, then (with `path`) the compute backend's pure-RT one and the path
/// tracer's, named.
fn frames(scene: &Scene, path: bool) -> Vec<(String, FrameOutput)> {
    frames_with(scene, path, AmbientMode::default())
}

fn frames_with(scene: &Scene, path: bool, ambient: AmbientMode) -> Vec<(String, FrameOutput)> {
    let cam = &scene.cameras[0];
    let mut b = common::Bench::new(scene, W, H);
    let mut out = b.every_backend(scene, &RenderSettings { ambient, ..Default::default() });
    if path {
        let rt = RenderSettings { mode: Mode::Rt, backend: Backend::Compute, ambient, ..Default::default() };
        out.push(("pure RT Compute".into(), b.frame(scene, cam, &rt)));
        let settings = RenderSettings {
            mode: Mode::Path,
            backend: Backend::Compute,
            path: PathSettings { samples: 8, max_bounces: 4, ..Default::default() },
            ..Default::default()
        };
        let f =
            hybrid_rt::render::reference::render_converged(&mut b.renderer, &b.ctx, scene, cam, &settings);
        out.push(("path tracer".into(), f.unwrap()));
    }
    b.finish();
    out
}

/// A floor of material `m` under a constant sky, seen from above at 70 degrees' field.
fn floor(name: &str, m: Block) -> Scene {
    let toml = scene_toml([
        environment([SKY; 3]),
        no_light(),
        camera([0.0, 1.0, 0.0], [0.0, 0.0, -3.0]).yfov(70),
        m.set("name", "coated"),
        plane("floor", 400.0).material("coated"),
    ]);
    common::scene_from_toml(name, &toml)
}

/// common::floor_error over the sky.
fn floor_error(f: &FrameOutput, scene: &Scene, want: impl Fn(f64) -> f64) -> (f64, f64, f64) {
    let sky = SKY as f64;
    let (got, wanted, worst) = common::floor_error(f, &scene.cameras[0], want);
    (got / sky, wanted / sky, worst / sky)
}

#[test]
fn a_smooth_coat_reflects_its_fresnel_weighted_by_its_factor() {
    for c in [1.0f32, 0.5] {
        // Base roughness 1: only the coat is a mirror.
        let m =
            material("m").base([0.0; 3]).roughness(1.0).specular(0.0).clearcoat(c).clearcoat_roughness(0.0);
        let scene = floor(&format!("clearcoat_smooth_{c}"), m);
        for (what, f) in frames(&scene, true) {
            // The coat's mirror ray (under a constant sky the split sum would come close too).
            if !what.starts_with("path") {
                assert!(
                    f.timings.iter().any(|(p, _)| *p == "specular"),
                    "{what}: no `specular` pass: {:?}",
                    f.timings
                );
            }
            let (got, want, worst) =
                floor_error(&f, &scene, |cos| SKY as f64 * c as f64 * (0.04 + 0.96 * (1.0 - cos).powi(5)));
            println!("coat {c}, {what}: floor mean {got:.4} against {want:.4}, worst |error| {worst:.4} of the sky");
            // The path tracer jitters its samples within the pixel (the closed form is at its centre).
            let bound = if what.starts_with("path") { 0.05 } else { 0.002 };
            assert!(worst < bound, "coat {c}, {what}: a pixel is {worst:.4} of the sky off the closed form");
            assert!((got - want).abs() < 0.002, "coat {c}, {what}: the mean is off the closed form");
        }
    }
}

#[test]
fn a_rough_coat_reflects_the_sky_as_the_path_tracer_does() {
    // Over a floor that reflects nothing itself the coat alone shows; over a grey diffuse floor the
    // layer under it keeps what the coat lets through.
    for (base, specular) in [(0.0f32, 0.0f32), (0.2, 1.0)] {
        let m = material("m")
            .base([base; 3])
            .roughness(1.0)
            .specular(specular)
            .clearcoat(1.0)
            .clearcoat_roughness(0.5);
        let coated = floor(&format!("clearcoat_rough_{base}"), m.clone());
        let bare = floor(&format!("clearcoat_bare_{base}"), m.clearcoat(0.0));
        let frames_coated = frames(&coated, true);
        let truth = &frames_coated.last().unwrap().1;
        let (truth_mean, ..) = floor_error(truth, &coated, |_| 0.0);
        let (bare_mean, ..) = floor_error(&frames(&bare, false)[0].1, &bare, |_| 0.0);
        println!("base {base}: the path tracer's floor mean {truth_mean:.4} of the sky, without the coat {bare_mean:.4}");
        assert!(
            (truth_mean - bare_mean).abs() > 0.02,
            "base {base}: the coat changes the floor by only {:.4} of the sky",
            (truth_mean - bare_mean).abs()
        );
        for (what, f) in &frames_coated[..frames_coated.len() - 1] {
            let (got, ..) = floor_error(f, &coated, |_| 0.0);
            println!("base {base}, {what}: floor mean {got:.4} of the sky");
            assert!(
                (got - truth_mean).abs() < 0.01,
                "base {base}, {what}: floor mean {got:.4} against the path tracer's {truth_mean:.4}"
            );
        }
    }
}

#[test]
fn a_glossy_coat_reflects_what_stands_on_it() {
    // A coat of roughness 0.3 over a floor that reflects nothing itself, a sunlit white wall standing
    // on it under a dim sky: the coat's glossy rays find the wall where the split sum sees the sky.
    let toml = scene_toml([
        environment([0.3; 3]),
        directional([0.3, -0.5, -1.0], 3.0),
        camera([0.0, 0.6, 1.5], [0.0, 0.2, -3.0]).yfov(60),
        material("coat").base([0.0; 3]).roughness(1.0).specular(0.0).clearcoat(1.0).clearcoat_roughness(0.3),
        lambert("wall", [0.8; 3]),
        plane("floor", 400.0).material("coat"),
        plane("wall", 6.0).at([0.0, 0.0, -3.0]).rot([90.0, 0.0, 0.0]).material("wall"),
    ]);
    let scene = common::scene_from_toml("clearcoat_glossy", &toml);
    let cam = &scene.cameras[0];
    // Floor pixels in front of the wall (their camera ray meets y = 0 before z = -3).
    let floor_mean = |f: &FrameOutput| {
        let (mut sum, mut n) = (0.0f64, 0);
        for y in 0..H {
            for x in 0..W {
                let (o, d) = common::pixel_ray(cam, W, H, x, y);
                let t = -o.y / d.y;
                if d.y < -0.02 && o.z + t * d.z > -2.9 {
                    sum += f.hdr[((y * W + x) * 4 + 1) as usize] as f64;
                    n += 1;
                }
            }
        }
        assert!(n > (W * H / 4) as usize, "the floor before the wall: {n} pixels");
        sum / n as f64
    };
    let runs = frames(&scene, true);
    let truth = floor_mean(&runs.last().unwrap().1);
    let mut b = common::Bench::new(&scene, W, H);
    let unreflected = RenderSettings {
        effects: Effects { reflections: false, ..Default::default() },
        ..Default::default()
    };
    let split_sum = floor_mean(&b.frame(&scene, cam, &unreflected));
    b.finish();
    println!("the path tracer's floor mean {truth:.4}; without reflection rays {split_sum:.4}");
    assert!((split_sum - truth).abs() > 0.1 * truth, "the wall barely shows in the coat");
    for (what, f) in &runs[..runs.len() - 1] {
        let got = floor_mean(f);
        println!("{what}: floor mean {got:.4} ({:+.1} % of the truth)", 100.0 * (got / truth - 1.0));
        assert!(
            (got - truth).abs() < 0.05 * truth,
            "{what}: floor mean {got:.4} against the truth's {truth:.4}"
        );
    }
}

/// A quad of `material` standing on a mirror floor before a wall under a sky and a sun; `texture` is
/// its one image.
fn quad_scene(name: &str, texture: image::Rgba<u8>, material: &str) -> Scene {
    let img = image::RgbaImage::from_pixel(4, 4, texture);
    let uvs = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let quad = common::scenes::quad_gltf(&format!("{name}.gltf"), 1.0, uvs, &img, material);
    let toml = scene_toml([
        environment([0.9, 0.8, 0.7]),
        directional([0.2, -0.6, -1.0], 3.0),
        camera([0.8, 1.4, 5.5], [0.0, 0.5, 0.0]).yfov(50),
        mirror("mirror", [0.9; 3]),
        lambert("wall", [0.2, 0.5, 0.8]),
        plane("floor", 8.0).material("mirror"),
        plane("wall", 8.0).at([0.0, 0.0, -3.0]).rot([90.0, 0.0, 0.0]).material("wall"),
        gltf("quad", quad.display()).at([0.0, 1.05, 0.0]).rot([0.0, 20.0, 0.0]),
    ]);
    common::scene_from_toml(name, &toml)
}

/// A glTF material with `base` (pbrMetallicRoughness members) and `extra` (further members).
fn gltf_material(base: &str, extra: &str) -> String {
    format!(r#"{{"name": "coated", "doubleSided": true, "pbrMetallicRoughness": {{{base}}}{extra}}}"#)
}

fn assert_same(what: &str, a: &[(String, FrameOutput)], b: &[(String, FrameOutput)]) {
    for ((run, x), (_, y)) in a.iter().zip(b) {
        let (worst, share) = hybrid_rt::image_diff::diff_stats(x.rgb8().as_raw(), y.rgb8().as_raw(), 3, 2);
        println!("{what}, {run}: {:.3} % of pixels differ > 2/255, largest {worst}/255", 100.0 * share);
        assert!(share < 0.002, "{what}, {run}: {:.3} % of pixels differ", 100.0 * share);
    }
}

fn assert_apart(what: &str, a: &[(String, FrameOutput)], b: &[(String, FrameOutput)]) {
    let (worst, share) =
        hybrid_rt::image_diff::diff_stats(a[0].1.rgb8().as_raw(), b[0].1.rgb8().as_raw(), 3, 2);
    println!("{what}: {:.1} % of pixels differ, largest {worst}/255", 100.0 * share);
    assert!(share > 0.02, "{what}: only {:.2} % of pixels differ", 100.0 * share);
}

#[test]
fn coat_textures_render_as_the_factors_they_hold() {
    // R: weight 128/255; G: roughness 77/255 (a glossy coat: the split sum and the sun's highlight).
    let texel = image::Rgba([128, 77, 0, 255]);
    let base = r#""baseColorFactor": [0.1, 0.4, 0.2, 1], "metallicFactor": 0.0, "roughnessFactor": 0.7"#;
    let coat = |members: &str| format!(r#", "extensions": {{"KHR_materials_clearcoat": {{{members}}}}}"#);
    let textures = coat(
        r#""clearcoatFactor": 1, "clearcoatTexture": {"index": 0}, "clearcoatRoughnessFactor": 1, "clearcoatRoughnessTexture": {"index": 0}"#,
    );
    let factors = coat(&format!(
        r#""clearcoatFactor": {}, "clearcoatRoughnessFactor": {}"#,
        128.0 / 255.0,
        77.0 / 255.0
    ));
    let with_textures =
        frames(&quad_scene("clearcoat_textures", texel, &gltf_material(base, &textures)), false);
    let with_factors = frames(&quad_scene("clearcoat_factors", texel, &gltf_material(base, &factors)), false);
    let without = frames(&quad_scene("clearcoat_none", texel, &gltf_material(base, "")), false);
    assert_same("coat textures against their factors", &with_textures, &with_factors);
    assert_apart("the coat against none", &with_textures, &without);
}

#[test]
fn the_coat_follows_its_own_normal_map_not_the_bases() {
    // A normal map tilted ~38 degrees about the quad's v axis.
    let texel = image::Rgba([200, 128, 220, 255]);
    // A base that reflects nothing itself (black, specular weight 0) under a glossy coat: only the
    // coat shows, so the base's normal map must not change the image. With the SH ambient: the
    // traced ambient's visibility (the coat's specular occlusion too) is sampled about the base's
    // shading normal.
    let base = r#""baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0, "roughnessFactor": 1.0"#;
    let coat = |normal: &str, base_map: &str| {
        format!(
            r#"{base_map}, "extensions": {{"KHR_materials_specular": {{"specularFactor": 0}},
            "KHR_materials_clearcoat": {{"clearcoatFactor": 1, "clearcoatRoughnessFactor": 0.15{normal}}}}}"#
        )
    };
    let base_mapped = coat("", r#", "normalTexture": {"index": 0}"#);
    let plain = coat("", "");
    let coat_mapped = coat(r#", "clearcoatNormalTexture": {"index": 0}"#, "");
    let a = frames_with(
        &quad_scene("clearcoat_base_normal", texel, &gltf_material(base, &base_mapped)),
        false,
        AmbientMode::Sh,
    );
    let b = frames_with(
        &quad_scene("clearcoat_plain_normal", texel, &gltf_material(base, &plain)),
        false,
        AmbientMode::Sh,
    );
    let c = frames_with(
        &quad_scene("clearcoat_coat_normal", texel, &gltf_material(base, &coat_mapped)),
        false,
        AmbientMode::Sh,
    );
    assert_same("a coat over a normal-mapped base against an unmapped one", &a, &b);
    assert_apart("a coat with its own normal map against one without", &c, &b);
}
