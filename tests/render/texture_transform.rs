//! KHR_texture_transform: a quad whose every texture reference (base colour with an alpha mask,
//! metallic-roughness, normal, emissive) carries an offset, a rotation and an anisotropic scale
//! renders as the same quad with the transform baked into its vertex UVs — seen directly and in a
//! mirror floor, on every backend, in both modes and by the path tracer. The mirror's hits pick their
//! mip by the ray cone, whose uv footprint the transform scales (scene.glsl `uv_lod_shift`); the
//! camera rays of pure RT use transformed uv gradients. The same quad with its UVs untransformed is
//! far off: the comparison sees the transform.
use crate::common;

use common::toml::*;
use hybrid_rt::render::shading::{Backend, Mode};
use hybrid_rt::render::{FrameOutput, PathSettings, RenderSettings};
use hybrid_rt::scene::UvTransform;

const W: u32 = 96;
const H: u32 = 64;

/// 64 x 64 texels in 8 x 8 cells of distinct colours with a ramp inside each cell, and two cells
/// cut out (alpha 0).
fn pattern() -> image::RgbaImage {
    image::RgbaImage::from_fn(64, 64, |x, y| {
        let (cx, cy) = (x / 8, y / 8);
        let hole = cx == 3 && (cy == 2 || cy == 5);
        image::Rgba([
            (cx * 30 + (x % 8) * 3) as u8,
            (cy * 30 + (y % 8) * 3) as u8,
            if (cx + cy) % 2 == 0 { 220 } else { 40 },
            if hole { 0 } else { 255 },
        ])
    })
}

const CORNERS: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];

fn transform() -> UvTransform {
    UvTransform::from_gltf([0.3, -0.2], 0.7, [2.5, 1.5])
}

/// The quad with (`extension`) or without the transform on every reference, at `uvs`.
fn quad(file: &str, uvs: [[f32; 2]; 4], extension: bool) -> std::path::PathBuf {
    let ext = if extension {
        r#", "extensions": {"KHR_texture_transform": {"offset": [0.3, -0.2], "rotation": 0.7, "scale": [2.5, 1.5]}}"#
    } else {
        ""
    };
    let material = format!(
        r#"{{"name": "tiled", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": true,
    "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0{ext}}}, "metallicRoughnessTexture": {{"index": 0{ext}}},
      "metallicFactor": 0.6, "roughnessFactor": 1.0}},
    "normalTexture": {{"index": 0{ext}}}, "emissiveTexture": {{"index": 0{ext}}}, "emissiveFactor": [0.3, 0.3, 0.3]}}"#
    );
    common::scenes::quad_gltf(file, 1.0, uvs, &pattern(), &material)
}

/// The quad standing on a mirror floor, lit by a sun, seen from the front and above.
fn scene(name: &str, quad: &std::path::Path) -> hybrid_rt::scene::Scene {
    let toml = scene_toml([
        environment([0.3, 0.35, 0.4]),
        camera([0.8, 1.4, 5.5], [0.0, 0.5, 0.0]).yfov(50),
        directional([0.3, -1.0, -0.6], 3.0),
        mirror("mirror", [0.9; 3]),
        plane("floor", 8.0).material("mirror"),
        gltf("quad", quad.display()).at([0.0, 1.05, 0.0]).rot([0.0, 20.0, 0.0]),
    ]);
    common::scene_from_toml(name, &toml)
}

/// (share of pixels differing by more than 3/255 in a channel, largest difference / 255).
fn difference(a: &FrameOutput, b: &FrameOutput) -> (f64, u8) {
    let (max, share) = hybrid_rt::image_diff::diff_stats(a.rgb8().as_raw(), b.rgb8().as_raw(), 3, 3);
    (share, max)
}

fn render(b: &mut common::Bench, scene: &hybrid_rt::scene::Scene, settings: &RenderSettings) -> FrameOutput {
    let cam = &scene.cameras[0];
    if settings.mode == Mode::Path {
        return hybrid_rt::render::reference::render_converged(&mut b.renderer, &b.ctx, scene, cam, settings)
            .unwrap();
    }
    b.frame(scene, cam, settings)
}

#[test]
fn a_texture_transform_renders_as_the_uvs_it_maps_to() {
    let t = transform();
    let transformed = scene("texture_transform_ext", &quad("transform_ext.gltf", CORNERS, true));
    let baked =
        scene("texture_transform_baked", &quad("transform_baked.gltf", CORNERS.map(|uv| t.apply(uv)), false));
    let plain = scene("texture_transform_plain", &quad("transform_plain.gltf", CORNERS, false));
    let mut runs: Vec<(String, RenderSettings)> = common::BACKENDS
        .iter()
        .map(|&backend| (format!("hybrid {backend:?}"), RenderSettings { backend, ..Default::default() }))
        .collect();
    runs.push((
        "pure RT Compute".into(),
        RenderSettings { mode: Mode::Rt, backend: Backend::Compute, ..Default::default() },
    ));
    runs.push((
        "path tracer Compute".into(),
        RenderSettings {
            mode: Mode::Path,
            backend: Backend::Compute,
            path: PathSettings { samples: 4, max_bounces: 3, ..Default::default() },
            ..Default::default()
        },
    ));
    let mut benches = [&transformed, &baked, &plain].map(|s| common::Bench::new(s, W, H));
    for (what, settings) in &runs {
        let got = render(&mut benches[0], &transformed, settings);
        let want = render(&mut benches[1], &baked, settings);
        if std::env::var_os("TT_DUMP").is_some() {
            got.rgb8().save(format!("/tmp/tt_{what}.png")).unwrap();
        }
        let (share, worst) = difference(&got, &want);
        println!(
            "{what}: transformed vs baked UVs: {:.3} % of pixels differ > 3/255, largest {worst}/255",
            100.0 * share
        );
        assert!(share < 0.002, "{what}: {:.3} % of pixels differ from the baked UVs", 100.0 * share);
        if what.starts_with("hybrid") {
            let (share, worst) = difference(&got, &render(&mut benches[2], &plain, settings));
            println!(
                "{what}: transformed vs untransformed UVs: {:.1} % differ, largest {worst}/255",
                100.0 * share
            );
            assert!(share > 0.1, "{what}: the transform barely shows ({:.1} %)", 100.0 * share);
        }
    }
    for b in benches {
        b.finish();
    }
}
