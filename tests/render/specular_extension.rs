//! KHR_materials_specular (glsl/common/brdf.glsl `surface_f0` / `surface_f90`; the G-buffer does not
//! store it, gbuffer_read.glsl `primary_specular` looks it up):
//!
//! - A smooth black dielectric floor under a constant sky reflects L x F(theta), F the Schlick curve
//!   from w x F0 to w (the weight scales the whole curve): per pixel, every backend and the path
//!   tracer (its mean; pixels within its jitter), for weights 1, 0.5 and 0.
//! - Its colour multiplies the IOR's F0: IOR 1.5 tinted by 4 renders as IOR 7/3 (F0 0.16), and
//!   weight 0 as IOR 1 (nothing reflected), on glossy and rough spheres too.
//! - Its textures (A: weight, RGB sRGB: colour) render as the factors they hold, seen directly and in
//!   a mirror.
use crate::common;

use common::toml::*;
use hybrid_rt::render::shading::{Backend, Mode};
use hybrid_rt::render::{FrameOutput, PathSettings, RenderSettings};
use hybrid_rt::scene::Scene;

const W: u32 = 64;
const H: u32 = 48;
const SKY: f32 = 2.0;

fn path_settings() -> RenderSettings {
    RenderSettings {
        mode: Mode::Path,
        backend: Backend::Compute,
        path: PathSettings { samples: 4, max_bounces: 4, ..Default::default() },
        ..Default::default()
    }
}

/// Every backend's hybrid frame, then the path tracer's (named).
fn frames(scene: &Scene) -> Vec<(String, FrameOutput)> {
    let cam = &scene.cameras[0];
    let mut b = common::Bench::new(scene, W, H);
    let mut out = b.every_backend(scene, &RenderSettings::default());
    let path =
        hybrid_rt::render::reference::render_converged(&mut b.renderer, &b.ctx, scene, cam, &path_settings());
    out.push(("path tracer".into(), path.unwrap()));
    b.finish();
    out
}

#[test]
fn the_weight_scales_the_whole_fresnel_curve_of_a_smooth_floor() {
    for weight in [1.0f32, 0.5, 0.0] {
        let toml = scene_toml([
            environment([SKY; 3]),
            no_light(),
            camera([0.0, 1.0, 0.0], [0.0, 0.0, -3.0]).yfov(70),
            material("black").base([0.0; 3]).roughness(0.0).specular(weight),
            plane("floor", 400.0).material("black"),
        ]);
        let scene = common::scene_from_toml(&format!("specular_floor_{weight}"), &toml);
        let cam = &scene.cameras[0];
        for (what, f) in frames(&scene) {
            let f0 = weight as f64 * 0.04;
            let (got, want, worst) = common::floor_error(&f, cam, |c| {
                SKY as f64 * (f0 + (weight as f64 - f0) * (1.0 - c).powi(5))
            });
            let worst = worst / SKY as f64;
            println!("weight {weight}, {what}: floor mean {got:.4} against {want:.4}, worst |error| {worst:.4} of the sky");
            // The path tracer jitters its samples within the pixel (the closed form is at its centre).
            let bound = if what.starts_with("path") { 0.05 } else { 0.002 };
            assert!(
                worst < bound,
                "weight {weight}, {what}: a pixel is {worst:.4} of the sky off the closed form"
            );
            let mean = (got - want).abs() / SKY as f64;
            assert!(mean < 0.002, "weight {weight}, {what}: the mean is {mean:.4} of the sky off");
        }
    }
}

/// Spheres of roughness 0.05 (traced mirror), 0.3 (glossy) and 0.8 (split sum) of material `m` on a
/// grey floor under a sky and a sun.
fn spheres(name: &str, m: Block) -> Scene {
    let toml = scene_toml([
        environment([0.6, 0.7, 0.9]),
        directional([0.4, -1.0, -0.5], 3.0),
        camera([0.0, 1.6, 4.5], [0.0, 0.5, 0.0]).yfov(50),
        lambert("floor", [0.5; 3]),
        m.clone().set("name", "smooth").roughness(0.05),
        m.clone().set("name", "glossy").roughness(0.3),
        m.set("name", "rough").roughness(0.8),
        plane("floor", 20.0).material("floor"),
        sphere("a", 0.6).at([-1.4, 0.6, 0.0]).material("smooth"),
        sphere("b", 0.6).at([0.0, 0.6, 0.0]).material("glossy"),
        sphere("c", 0.6).at([1.4, 0.6, 0.0]).material("rough"),
    ]);
    common::scene_from_toml(name, &toml)
}

/// (share of pixels differing by more than 2/255 in a channel, largest difference / 255).
fn difference(a: &FrameOutput, b: &FrameOutput) -> (f64, u8) {
    let (max, share) = hybrid_rt::image_diff::diff_stats(a.rgb8().as_raw(), b.rgb8().as_raw(), 3, 2);
    (share, max)
}

fn assert_same(
    what: &str,
    a: &[(String, FrameOutput)],
    b: &[(String, FrameOutput)],
    apart: &[(String, FrameOutput)],
) {
    for ((run, x), (_, y)) in a.iter().zip(b) {
        let (share, worst) = difference(x, y);
        println!("{what}, {run}: {:.3} % of pixels differ > 2/255, largest {worst}/255", 100.0 * share);
        assert!(share < 0.002, "{what}, {run}: {:.3} % of pixels differ", 100.0 * share);
    }
    // The comparison sees the extension: without it the image is another.
    let (share, worst) = difference(&a[0].1, &apart[0].1);
    println!(
        "{what}: against the material without the extension {:.1} % differ, largest {worst}/255",
        100.0 * share
    );
    assert!(share > 0.05, "{what}: the extension barely shows ({:.2} %)", 100.0 * share);
}

#[test]
fn the_colour_multiplies_the_f0_of_the_ior() {
    let plain = frames(&spheres("specular_plain", material("m").base([0.2, 0.3, 0.6]).ior(1.5)));
    let tinted = frames(&spheres(
        "specular_tinted",
        material("m").base([0.2, 0.3, 0.6]).ior(1.5).specular_color([4.0; 3]),
    ));
    // ((n - 1) / (n + 1))^2 = 0.16 = 4 x 0.04.
    let ior = frames(&spheres("specular_ior", material("m").base([0.2, 0.3, 0.6]).ior(7.0 / 3.0)));
    assert_same("IOR 1.5 tinted by 4 against IOR 7/3", &tinted, &ior, &plain);
    let off = frames(&spheres("specular_off", material("m").base([0.2, 0.3, 0.6]).specular(0.0)));
    let ior_one = frames(&spheres("specular_ior_one", material("m").base([0.2, 0.3, 0.6]).ior(1.0)));
    assert_same("weight 0 against IOR 1", &off, &ior_one, &plain);
}

/// A quad (specular textures, the factors they hold, or neither) standing on a mirror floor.
fn textured(name: &str, textures: Option<bool>) -> Scene {
    // A: weight 128/255; RGB: sRGB 188 -> linear 0.5029.
    let img = image::RgbaImage::from_pixel(4, 4, image::Rgba([188, 188, 188, 128]));
    let c = ((188.0f64 / 255.0 + 0.055) / 1.055).powf(2.4);
    let ext = match textures {
        Some(true) => {
            r#", "extensions": {"KHR_materials_specular": {"specularTexture": {"index": 0}, "specularColorTexture": {"index": 0}}}"#
                .to_string()
        }
        Some(false) => format!(
            r#", "extensions": {{"KHR_materials_specular": {{"specularFactor": {}, "specularColorFactor": [{c}, {c}, {c}]}}}}"#,
            128.0 / 255.0
        ),
        None => String::new(),
    };
    let material = format!(
        r#"{{"name": "coated", "doubleSided": true{ext},
    "pbrMetallicRoughness": {{"baseColorFactor": [0.1, 0.4, 0.2, 1], "metallicFactor": 0.0, "roughnessFactor": 0.2}}}}"#
    );
    let uvs = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let quad = common::scenes::quad_gltf(&format!("{name}.gltf"), 1.0, uvs, &img, &material);
    let toml = scene_toml([
        environment([0.9, 0.8, 0.7]),
        directional([0.2, -0.6, -1.0], 3.0),
        camera([0.8, 1.4, 5.5], [0.0, 0.5, 0.0]).yfov(50),
        mirror("mirror", [0.9; 3]),
        plane("floor", 8.0).material("mirror"),
        gltf("quad", quad.display()).at([0.0, 1.05, 0.0]).rot([0.0, 20.0, 0.0]),
    ]);
    common::scene_from_toml(name, &toml)
}

#[test]
fn specular_textures_render_as_the_factors_they_hold() {
    let with_textures = frames(&textured("specular_textures", Some(true)));
    let with_factors = frames(&textured("specular_factors", Some(false)));
    let without = frames(&textured("specular_none", None));
    assert_same("specular textures against their factors", &with_textures, &with_factors, &without);
}
