//! The command line end to end: the no-argument default render, `info`, and
//! bad input, each of which must give a clear error naming the problem, a
//! non-zero exit code and no panic.
use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub(crate) fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    c.env("HYBRID_RT_VALIDATION", "1");
    c
}

pub(crate) fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// At a fixed exposure: the glTF files here author none, which would auto-expose them.
fn render_scene(scene: &Path, out_dir: &Path) -> Output {
    bin()
        .args(["render", "--width", "64", "--height", "36", "--exposure", "1", "--scene"])
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

/// The triangle (0,0,0), (1,0,0), (0,1,0), framed by the default camera
/// from +z, lit brighter than the sky behind it: the bright pixels form a
/// right triangle with its vertical leg on the left and its widest row at
/// the bottom.
#[test]
fn valid_triangle_renders() {
    let d = tmp("valid");
    let scene = write_triangle_gltf(&d, |_, _| {});
    let out = render_scene(&scene, &d);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let img = image::open(d.join("x.png")).unwrap().to_luma8();
    // (first column, width) of each row's bright run (the sky is ~60, the
    // lit triangle ~110).
    let rows: Vec<(u32, u32)> = (0..img.height())
        .filter_map(|y| {
            let xs: Vec<u32> = (0..img.width()).filter(|&x| img.get_pixel(x, y)[0] > 90).collect();
            let (first, last) = (*xs.first()?, *xs.last()?);
            assert_eq!(last - first + 1, xs.len() as u32, "row {y}: the bright pixels are not one run");
            Some((first, xs.len() as u32))
        })
        .collect();
    let covered: u32 = rows.iter().map(|r| r.1).sum();
    let share = covered as f64 / (img.width() * img.height()) as f64;
    assert!(rows.len() >= 8 && (0.05..0.5).contains(&share), "{} rows, {share:.3} of the image", rows.len());
    let left = rows.iter().map(|r| r.0);
    assert!(left.clone().max().unwrap() - left.min().unwrap() <= 2, "no vertical leg on the left: {rows:?}");
    assert!(rows.windows(2).all(|w| w[1].1 + 1 >= w[0].1), "rows do not widen downwards: {rows:?}");
    assert!(rows.last().unwrap().1 >= 5 * rows[0].1, "not a triangle: {rows:?}");

    // Where the camera puts it: a pixel whose ray, and its neighbours' rays,
    // all hit the triangle (z = 0, x >= 0, y >= 0, x + y <= 1) shows it; one
    // whose rays all miss shows the sky (pixels on the edge are left out).
    let camera = &hybrid_rt::scene::Scene::load(&scene).unwrap().cameras[0];
    let (w, h) = img.dimensions();
    let hits = |x: u32, y: u32| {
        let (o, d) = common::pixel_ray(camera, w, h, x, y);
        let p = o + d * (-o.z / d.z);
        d.z < 0.0 && p.x >= 0.0 && p.y >= 0.0 && p.x + p.y <= 1.0
    };
    let (mut inside, mut outside) = (0, 0);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let around = [(x, y), (x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)].map(|(x, y)| hits(x, y));
            let luma = img.get_pixel(x, y)[0];
            if around.iter().all(|&hit| hit) {
                assert!(luma > 90, "({x}, {y}) is on the triangle but {luma} (sky ~60, triangle ~110)");
                inside += 1;
            } else if around.iter().all(|&hit| !hit) {
                assert!(luma <= 90, "({x}, {y}) is sky but {luma} (sky ~60, triangle ~110)");
                outside += 1;
            }
        }
    }
    assert!(inside >= 100 && outside >= 500, "{inside} pixels on the triangle, {outside} off it");
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

/// One device block of `info`: its header line and "key: value" lines.
struct InfoDevice {
    header: String,
    fields: Vec<(String, String)>,
    selected: bool,
}

impl InfoDevice {
    fn field(&self, key: &str) -> &str {
        self.fields
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
            .unwrap_or_else(|| panic!("{}: no '{key}' line", self.header))
    }
}

fn parse_info(s: &str) -> Vec<InfoDevice> {
    let mut devices: Vec<InfoDevice> = Vec::new();
    for line in s.lines() {
        if line.starts_with("device ") {
            devices.push(InfoDevice { header: line.to_string(), fields: Vec::new(), selected: false });
            continue;
        }
        let d = devices.last_mut().unwrap_or_else(|| panic!("text before the first device:\n{s}"));
        if line.trim() == "(selected)" {
            d.selected = true;
        } else if let Some((k, v)) = line.trim().split_once(": ") {
            d.fields.push((k.to_string(), v.to_string()));
        }
    }
    devices
}

/// `info` prints, for every device, its name and an explicit yes/no per
/// capability equal to what the device reports (checked here against the
/// device's extension list), and marks exactly the device `auto` selects.
#[test]
fn info_reports_devices() {
    let out = bin().arg("info").output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s = String::from_utf8_lossy(&out.stdout);
    let printed = parse_info(&s);

    let instance = hybrid_rt::vk::Instance::new(&Default::default()).unwrap();
    let devices = hybrid_rt::vk::device::enumerate(&instance.raw, instance.api_version).unwrap();
    assert_eq!(printed.len(), devices.len(), "one block per device:\n{s}");
    let (_, chosen) = hybrid_rt::vk::device::select(&devices, &Default::default()).unwrap();
    let yn = |b: bool| if b { "yes" } else { "no" };
    for ((pd, caps), p) in devices.iter().zip(&printed) {
        let expected_header = format!("device {}: {} (", caps.index, caps.name);
        assert!(p.header.starts_with(&expected_header), "'{}' is not '{expected_header}...'", p.header);
        assert_eq!(p.selected, caps.index == chosen.index, "{}: selection mark wrong:\n{s}", p.header);
        // Independent of the capability query: what the driver lists.
        let exts = unsafe { instance.raw.enumerate_device_extension_properties(*pd) }.unwrap();
        let has = |name: &std::ffi::CStr| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
        for (key, value, ext) in [
            ("acceleration structures", caps.acceleration_structure, ash::khr::acceleration_structure::NAME),
            ("ray query", caps.ray_query, ash::khr::ray_query::NAME),
            ("ray-tracing pipeline", caps.ray_tracing_pipeline, ash::khr::ray_tracing_pipeline::NAME),
        ] {
            assert_eq!(p.field(key), yn(value), "{}: {key}", p.header);
            assert!(!value || has(ext), "{}: {key} yes without {ext:?}", p.header);
        }
        let ts = p.field("timestamps");
        assert!(ts.starts_with(&format!("{} (", yn(caps.timestamps))), "{}: timestamps '{ts}'", p.header);
    }
    assert_eq!(printed.iter().filter(|p| p.selected).count(), 1, "exactly one device selected:\n{s}");
}

/// With --no-rt, `info` still shows what the device has, but says next to
/// each ray-tracing capability that --no-rt disabled it.
#[test]
fn info_with_no_rt_says_ray_tracing_is_disabled() {
    let out = bin().args(["--no-rt", "info"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s = String::from_utf8_lossy(&out.stdout);
    let (first, rest) = s.split_once('\n').unwrap();
    assert!(first.starts_with("ray-tracing extensions disabled by --no-rt"), "no --no-rt note first:\n{s}");
    let printed = parse_info(rest);
    assert!(!printed.is_empty());
    for p in &printed {
        for key in ["acceleration structures", "ray query", "ray-tracing pipeline"] {
            let v = p.field(key);
            assert!(v == "no" || v == "yes, disabled by --no-rt", "{}: {key}: '{v}'", p.header);
        }
    }
    assert!(s.contains("ray query: yes, disabled by --no-rt"), "lavapipe has ray queries:\n{s}");
}

/// A backend --no-rt disabled is reported as disabled by --no-rt, not as
/// missing from the device.
#[test]
fn no_rt_render_with_query_backend_names_no_rt() {
    let d = tmp("nortquery");
    let out = bin()
        .args(["--no-rt", "render", "--width", "16", "--height", "16", "--backend", "query", "--out"])
        .arg(d.join("x.png"))
        .output()
        .unwrap();
    assert_clean_failure(&out, &["--backend query", "disabled by --no-rt"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("has no usable"), "claims the device lacks it:\n{stderr}");
}

/// --validation says at info level that the layer is on.
#[test]
fn validation_is_confirmed_in_the_log() {
    let d = tmp("valconfirm");
    let out = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
        .env_remove("HYBRID_RT_VALIDATION")
        .env_remove("RUST_LOG")
        .args(["--validation", "render", "--width", "16", "--height", "16", "--out"])
        .arg(d.join("x.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.lines().any(|l| l.contains(" INFO ") && l.contains("VK_LAYER_KHRONOS_validation is on")),
        "no info line confirming the layer:\n{stderr}"
    );
}

fn bench_small(extra: &[&str]) -> Output {
    bin()
        .args(["--no-rt", "bench", "--width", "16", "--height", "16", "--frames", "1", "--warmup", "0"])
        .args(extra)
        .output()
        .unwrap()
}

/// A benchmark asked for a backend the device cannot run fails (naming it)
/// instead of skipping it and exiting 0.
#[test]
fn bench_with_an_unavailable_backend_fails() {
    let out = bench_small(&["--backend", "query"]);
    assert_clean_failure(&out, &["query", "--no-rt"]);
    let out = bench_small(&["--compare-backends"]);
    assert_clean_failure(&out, &["query", "pipeline", "--no-rt"]);
    let out = bench_small(&["--backend", "compute"]);
    assert!(out.status.success(), "compute: {}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("backend compute"), "no compute table");
}

/// The default scene is found next to the executable, whatever the current
/// directory: a copy of the binary with its own assets/default.toml loads
/// that one (the log says which).
#[test]
fn default_scene_is_found_next_to_the_executable() {
    let d = tmp("exedir");
    let exe_dir = d.join("bin");
    std::fs::create_dir_all(exe_dir.join("assets")).unwrap();
    let exe = exe_dir.join("hybrid-rt");
    std::fs::copy(env!("CARGO_BIN_EXE_hybrid-rt"), &exe).unwrap();
    let scene = exe_dir.join("assets/default.toml");
    std::fs::copy(common::repo_path("assets/default.toml"), &scene).unwrap();
    // Its environment map, which it names relative to itself.
    let probe = "assets/potsdamer_platz_512.hdr";
    std::fs::copy(common::repo_path(probe), exe_dir.join(probe)).unwrap();
    let cwd = d.join("elsewhere");
    std::fs::create_dir_all(&cwd).unwrap();
    let out = Command::new(&exe)
        .env("HYBRID_RT_VALIDATION", "1")
        .current_dir(&cwd)
        .args(["render", "--width", "16", "--height", "16", "--out", "x.png"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("scene {}", scene.display())),
        "does not load {}:\n{stderr}",
        scene.display()
    );
    assert!(cwd.join("x.png").exists());
}

/// Where the default scene cannot be found, the error says where it looked
/// and points to --scene.
#[test]
fn missing_default_scene_points_to_scene_flag() {
    let d = tmp("nodefault");
    let candidates = [d.join("assets/default.toml"), d.join("other/assets/default.toml")];
    let e = hybrid_rt::app::find_default_scene(&candidates).unwrap_err();
    let msg = format!("{e:#}");
    assert!(msg.contains("--scene"), "{msg}");
    for c in &candidates {
        assert!(msg.contains(&c.display().to_string()), "does not list {}: {msg}", c.display());
    }
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

/// Error exits after the device exists (a scene that fails to load, an
/// output that cannot be written after the frame was rendered) under
/// validation: a clear error, and no validation message, teardown included
/// (no leaked Vulkan object).
#[test]
fn error_exits_after_device_creation_leak_nothing() {
    let dir = tmp("error_exit");
    std::fs::write(dir.join("bad.toml"), "[[object]]\nname = 1\n").unwrap();
    // A file where the output's directory should be.
    std::fs::write(dir.join("blocker"), b"").unwrap();
    let cases: [(Vec<std::ffi::OsString>, &str); 2] = [
        (vec!["--scene".into(), dir.join("bad.toml").into()], "bad.toml"),
        (
            vec![
                "--scene".into(),
                common::repo_path("assets/default.toml").into(),
                "--out".into(),
                dir.join("blocker").join("x.png").into(),
            ],
            "blocker",
        ),
    ];
    for (args, needle) in cases {
        let out = bin().args(["render", "--width", "32", "--height", "18"]).args(&args).output().unwrap();
        assert_clean_failure(&out, &[needle]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains("VK_LAYER_KHRONOS_validation is on"), "validation was not on:\n{stderr}");
        let messages: Vec<&str> =
            stderr.lines().filter(|l| l.contains(" vulkan]") || l.contains("VUID")).collect();
        assert!(messages.is_empty(), "validation messages on the error path: {messages:#?}");
    }
}

/// Every effect switch says what it turns off in `--help`.
#[test]
fn effect_switches_have_help() {
    let out = bin().args(["render", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    for (flag, words) in [
        ("--no-shadows", "shadow rays"),
        ("--no-reflections", "reflections: mirrors"),
        ("--no-refractions", "refractions"),
    ] {
        // Its description: the lines under the flag's own, up to the next flag's.
        let mut lines = help.lines().skip_while(|l| l.trim() != flag);
        assert!(lines.next().is_some(), "{flag} not on a line of its own in:\n{help}");
        let text: Vec<&str> = lines.take_while(|l| !l.trim_start().starts_with('-')).map(str::trim).collect();
        let text = text.join(" ");
        assert!(text.contains(words), "{flag}: its help is '{}'", text.trim());
    }
}

/// An 8-bit environment map loads, with a warning that it is not HDR.
#[test]
fn ldr_environment_map_is_warned_about() {
    let dir = tmp("ldr-env");
    let png = dir.join("sky.png");
    image::RgbImage::from_pixel(8, 4, image::Rgb([200, 220, 255])).save(&png).unwrap();
    let out = common::tiny_render_cmd()
        .arg("--env")
        .arg(&png)
        .arg("--out")
        .arg(dir.join("out.png"))
        .env("RUST_LOG", "warn")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("sky.png") && stderr.contains("not HDR"), "{stderr}");
    let hdr = dir.join("sky.hdr");
    image::Rgb32FImage::from_pixel(8, 4, image::Rgb([0.8, 0.9, 1.0])).save(&hdr).unwrap();
    let out = common::tiny_render_cmd()
        .arg("--env")
        .arg(&hdr)
        .arg("--out")
        .arg(dir.join("out2.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && !stderr.contains("not HDR"), "{stderr}");
}

/// A scene that authors no exposure (a glTF file) is auto-exposed: the frame measures its luminance;
/// `--exposure` (or a scene file's `[environment] exposure`) fixes it.
#[test]
fn a_scene_without_an_exposure_is_auto_exposed() {
    let d = tmp("auto-exposure");
    let scene = write_triangle_gltf(&d, |_, _| {});
    // The frame's pass list when rendering `scene` with `extra` flags.
    let passes = |scene: &std::path::Path, extra: &[&str]| {
        let out = bin()
            .args(["render", "--width", "32", "--height", "18", "--log", "info", "--scene"])
            .arg(scene)
            .args(extra)
            .arg("--out")
            .arg(d.join("x.png"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{stderr}");
        let line = stderr.lines().find(|l| l.contains("frame: passes")).map(str::to_string);
        line.unwrap_or_else(|| panic!("no pass list in: {stderr}"))
    };
    let auto = passes(&scene, &[]);
    assert!(auto.contains("luminance"), "{auto}");
    let fixed = passes(&scene, &["--exposure", "1"]);
    assert!(!fixed.contains("luminance"), "{fixed}");
    let toml = d.join("fixed.toml");
    std::fs::write(
        &toml,
        format!("[environment]\nexposure = 2.0\n\n[[object]]\nname = \"t\"\ngltf = {:?}\n", scene),
    )
    .unwrap();
    let authored = passes(&toml, &[]);
    assert!(!authored.contains("luminance"), "{authored}");
}

/// `view --help` lists the viewer's keys.
#[test]
fn view_help_lists_the_keys() {
    let out = bin().args(["view", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && help.contains("Keys:"), "{help}");
    for (key, what) in hybrid_rt::viewer::keys::KEYS {
        assert!(help.contains(key) && help.contains(what), "{key} not in:\n{help}");
    }
}

/// An unknown knob is a usage error like the others (exit 2, before any
/// rendering): the message names the flag, the knob and every knob there is,
/// for `report --knobs`, `report knobs --knobs` and `report prt --knobs`.
#[test]
fn unknown_knob_is_a_usage_error_listing_the_knobs() {
    let d = tmp("unknown_knob");
    let _ = std::fs::remove_dir_all(&d);
    let names = |table: &[hybrid_rt::report::knobs::Knob]| table.iter().map(|k| k.name).collect::<Vec<_>>();
    let main_knobs = names(hybrid_rt::report::knobs::KNOBS);
    let prt_knobs = names(hybrid_rt::report::prt::PRT_KNOBS);
    for (args, knobs) in [
        (&["--knobs", "foo"][..], &main_knobs),
        (&["knobs", "--knobs", "foo"], &main_knobs),
        (&["prt", "--knobs", "foo"], &prt_knobs),
        (&["--prt", "--knobs", "foo"], &prt_knobs),
    ] {
        let out = bin().arg("report").args(args).arg("--out").arg(&d).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "report {args:?}: {stderr}");
        let line = stderr.lines().find(|l| l.starts_with("error:")).unwrap_or_else(|| panic!("{stderr}"));
        assert!(line.contains("--knobs") && line.contains("'foo'"), "report {args:?}: {line}");
        assert!(knobs.len() >= 3, "{knobs:?}");
        for k in knobs {
            assert!(line.contains(k), "report {args:?}: knob {k} not listed in {line}");
        }
        assert!(!stderr.contains("panicked") && !d.exists(), "report {args:?}: {stderr}");
    }
}

/// `report`'s subcommands take only their own options, each check reaches
/// through them (exit 2, the problem named, nothing written), and `report`
/// alone is `report knobs`.
#[test]
fn report_subcommands_take_their_own_options() {
    let d = tmp("report_subcommands");
    let _ = std::fs::remove_dir_all(&d);
    for (args, needle) in [
        (&["knobs", "--knobs", "depth"][..], "max-depth"),
        (&["knobs", "--frames", "3"], "at least 5"),
        (&["knobs", "--cases", "origin"], "unexpected argument '--cases'"),
        (&["stability", "--ref", "self"], "unexpected argument '--ref'"),
        (&["budget-paths", "--shares", "2"], "--shares"),
        (&["budget-paths"], "--shares"),
        (&["tone-sheet"], "--maps"),
        (&["tone-sheet", "--maps", "a.hdr", "--fps", "5", "--animation", "0"], "--fps has no effect"),
        (&["prt", "--frames", "3"], "at least 5"),
        (&["prt", "--knobs", "bands", "--shares", "1"], "unexpected argument '--shares'"),
        (&["prt", "--knobs", "foo"], "unknown knob 'foo' for report prt"),
    ] {
        let out = bin()
            .arg("report")
            .args(args)
            .args(["--width", "16", "--height", "9", "--out"])
            .arg(&d)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: '{needle}' not in {stderr}");
        assert!(!d.exists(), "{args:?} wrote {}", d.display());
    }
    let help = |sub: &str| {
        String::from_utf8_lossy(&bin().args(["report", sub, "--help"]).output().unwrap().stdout).to_string()
    };
    assert!(help("knobs").contains("--ref-samples") && !help("knobs").contains("--cases"));
    assert!(help("stability").contains("--cases") && !help("stability").contains("--ref-samples"));
    assert!(help("prt").contains("--sweep") && help("prt").contains("--reference-samples"));
}

/// On a software device the first frame says how far the shader compile is: a line per pass of the
/// frame, in the frame's order, counted against the total (the first run was silent for ~40 s).
#[test]
fn first_frame_reports_compile_progress() {
    let dir = tmp("compile_progress");
    let out = common::tiny_render_cmd()
        .arg("--out")
        .arg(dir.join("out.png"))
        .env("RUST_LOG", "info")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let passes: Vec<&str> = stderr
        .lines()
        .find_map(|l| l.split_once("frame: passes ").map(|(_, rest)| rest.trim()))
        .unwrap_or_else(|| panic!("no pass list:\n{stderr}"))
        .split(" -> ")
        .collect();
    let progress: Vec<(String, String)> = stderr
        .lines()
        .filter_map(|l| l.split_once("frame: [")?.1.split_once(" compiled and ran in "))
        .map(|(counted, _)| {
            let (k, name) = counted.split_once("] ").expect("[k/n] name");
            (k.to_string(), name.to_string())
        })
        .collect();
    let n = passes.len();
    let expected: Vec<(String, String)> =
        passes.iter().enumerate().map(|(i, p)| (format!("{}/{n}", i + 1), p.to_string())).collect();
    assert_eq!(progress, expected, "{stderr}");
}

/// A long load shows its stages (here every load: the threshold set to 0 ms through the environment),
/// as plain log lines when stderr is not a terminal, and ends with the total.
#[test]
fn a_load_shows_its_stages() {
    let dir = tmp("progress");
    let out = bin()
        .env("HYBRID_RT_PROGRESS_AFTER_MS", "0")
        .args(["render", "--width", "64", "--height", "36", "--backend", "compute", "--out"])
        .arg(dir.join("p.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| l.contains("load")).collect();
    let at = |needle: &str| {
        lines.iter().position(|l| l.contains(needle)).unwrap_or_else(|| panic!("no '{needle}' in {lines:#?}"))
    };
    // In load order, no terminal control characters.
    let stages = [
        at("): reading "),
        at("): uploading the scene"),
        at("): building the compute BVH"),
        at("): compiling the shaders of"),
        at("load: done in"),
    ];
    assert!(stages.windows(2).all(|w| w[0] < w[1]), "{lines:#?}");
    assert!(!stderr.contains('\r') && !stderr.contains('\x1b'), "terminal codes in a log");
}
