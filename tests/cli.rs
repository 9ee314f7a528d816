//! The command line end to end: the no-argument default render, `info`, and
//! bad input, each of which must give a clear error naming the problem, a
//! non-zero exit code and no panic.
mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    c.env("HYBRID_RT_VALIDATION", "1");
    c
}

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn render_scene(scene: &Path, out_dir: &Path) -> Output {
    bin()
        .args(["render", "--width", "64", "--height", "36", "--scene"])
        .arg(scene)
        .arg("--out")
        .arg(out_dir.join("x.png"))
        .output()
        .unwrap()
}

/// Asserts a failed run whose error names every `needle` and that did not panic.
fn assert_clean_failure(out: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "expected failure, got success; stderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "panicked:\n{stderr}");
    let error_line = stderr
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("no error line:\n{stderr}"));
    for n in needles {
        assert!(error_line.contains(n), "error does not mention '{n}': {error_line}");
    }
}

/// A one-triangle glTF with an external .bin: positions (3 x vec3) then
/// indices (3 x u16). `edit` may change the JSON and the binary.
fn write_triangle_gltf(dir: &Path, edit: impl FnOnce(&mut String, &mut Vec<u8>)) -> PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin.extend_from_slice(&[0, 0]); // pad to 4 bytes
    let mut json = r#"{
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0, "name": "tri"}],
  "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
  "materials": [{"name": "m", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]}}],
  "buffers": [{"uri": "tri.bin", "byteLength": 44}],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 36},
    {"buffer": 0, "byteOffset": 36, "byteLength": 6}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
  ]
}"#
    .to_string();
    edit(&mut json, &mut bin);
    std::fs::write(dir.join("tri.bin"), &bin).unwrap();
    let path = dir.join("tri.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

#[test]
fn valid_triangle_renders() {
    let d = tmp("valid");
    let scene = write_triangle_gltf(&d, |_, _| {});
    let out = render_scene(&scene, &d);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(d.join("x.png").exists());
}

#[test]
fn missing_file_is_named() {
    let d = tmp("missing");
    let out = render_scene(&d.join("nope.gltf"), &d);
    assert_clean_failure(&out, &["nope.gltf"]);
}

#[test]
fn unsupported_extension_is_named() {
    let d = tmp("ext");
    std::fs::write(d.join("scene.xyz"), "hello").unwrap();
    let out = render_scene(&d.join("scene.xyz"), &d);
    assert_clean_failure(&out, &["scene.xyz", "unsupported"]);
}

#[test]
fn truncated_glb_fails_cleanly() {
    let d = tmp("truncated");
    let src = std::fs::read(common::shared_asset("gltf/BoxAnimated/glTF-Binary/BoxAnimated.glb")).unwrap();
    let path = d.join("cut.glb");
    std::fs::write(&path, &src[..src.len() / 2]).unwrap();
    let out = render_scene(&path, &d);
    assert_clean_failure(&out, &["cut.glb"]);
}

#[test]
fn out_of_range_accessor_fails_cleanly() {
    let d = tmp("accessor");
    // The index accessor claims 300 elements in a 6-byte view.
    let scene = write_triangle_gltf(&d, |j, _| {
        *j = j.replace(r#""componentType": 5123, "count": 3"#, r#""componentType": 5123, "count": 300"#)
    });
    let out = render_scene(&scene, &d);
    assert_clean_failure(&out, &["tri.gltf"]);
}

#[test]
fn out_of_range_index_fails_cleanly() {
    let d = tmp("index");
    let scene = write_triangle_gltf(&d, |_, bin| {
        bin[36 + 4..36 + 6].copy_from_slice(&99u16.to_le_bytes());
    });
    let out = render_scene(&scene, &d);
    assert_clean_failure(&out, &["tri.gltf", "99"]);
}

#[test]
fn missing_buffer_file_is_named() {
    let d = tmp("nobin");
    let scene = write_triangle_gltf(&d, |j, _| *j = j.replace("\"tri.bin\"", "\"gone.bin\""));
    let out = render_scene(&scene, &d);
    assert_clean_failure(&out, &["gone.bin"]);
}

#[test]
fn missing_texture_file_is_named() {
    let d = tmp("notex");
    let scene = write_triangle_gltf(&d, |j, _| {
        *j = j
            .replace(
                r#""baseColorFactor": [1, 1, 1, 1]"#,
                r#""baseColorFactor": [1, 1, 1, 1], "baseColorTexture": {"index": 0}"#,
            )
            .replace(
                r#""buffers":"#,
                r#""textures": [{"source": 0}], "images": [{"uri": "absent.png"}], "buffers":"#,
            )
    });
    let out = render_scene(&scene, &d);
    assert_clean_failure(&out, &["absent.png"]);
}

#[test]
fn non_finite_vertex_is_named() {
    let d = tmp("nan");
    let scene = write_triangle_gltf(&d, |_, bin| bin[12..16].copy_from_slice(&f32::NAN.to_le_bytes()));
    let out = render_scene(&scene, &d);
    assert_clean_failure(&out, &["tri.gltf", "non-finite"]);
}

#[test]
fn bad_resolution_is_rejected() {
    let d = tmp("res");
    let out = bin()
        .args(["render", "--width", "0", "--height", "10", "--out"])
        .arg(d.join("x.png"))
        .output()
        .unwrap();
    assert_clean_failure(&out, &["resolution"]);
}

#[test]
fn no_arguments_renders_the_default_scene() {
    let d = tmp("noargs");
    // Without a display the no-argument run is the headless render.
    let out = bin().current_dir(&d).env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY").output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("out/default.png"), "does not say where it wrote:\n{stderr}");
    let img = image::open(d.join("out/default.png")).unwrap().into_rgb8();
    assert_eq!(img.dimensions(), (1280, 720));
    // Not a blank frame: many distinct colours.
    let mut colors: Vec<_> = img.pixels().map(|p| p.0).collect();
    colors.sort();
    colors.dedup();
    assert!(colors.len() > 500, "only {} distinct colours", colors.len());
}

#[test]
fn info_reports_devices() {
    let out = bin().arg("info").output().unwrap();
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(s.contains("ray query") && s.contains("(selected)"), "{s}");
}

/// Synchronization validation over every backend and over animated frames
/// (rigid and skinned; refit, rebuild and full rebuild): no hazard reported.
#[test]
fn synchronization_validation_is_clean() {
    let d = tmp("syncval");
    for backend in ["query", "pipeline", "compute"] {
        let out = bin()
            .args([
                "--sync-validation",
                "render",
                "--width",
                "96",
                "--height",
                "54",
                "--backend",
                backend,
                "--out",
            ])
            .arg(d.join(format!("{backend}.png")))
            .output()
            .unwrap();
        assert!(out.status.success(), "{backend}: {}", String::from_utf8_lossy(&out.stderr));
    }
    // Rigid (instances moved) and skinned (skinning -> refit / rebuild ->
    // top level, every kind of update) animation.
    for model in ["gltf/BoxAnimated/glTF/BoxAnimated.gltf", "gltf/CesiumMan/glTF/CesiumMan.gltf"] {
        let out = bin()
            .args([
                "--sync-validation",
                "bench",
                "--width",
                "96",
                "--height",
                "54",
                "--frames",
                "3",
                "--warmup",
                "0",
            ])
            .args(["--compare-backends", "--compare-accel-updates", "--animation", "0", "--scene"])
            .arg(common::shared_asset(model))
            .output()
            .unwrap();
        assert!(out.status.success(), "{model}: {}", String::from_utf8_lossy(&out.stderr));
    }
}
