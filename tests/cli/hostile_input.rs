//! Out-of-range numbers in glTF files are load errors naming file and
//! element; deep node chains load without recursion; cycles are rejected.

use std::path::PathBuf;

use hybrid_rt::scene::Scene;

use crate::common;
use common::base64;

fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join("hybrid-rt-tests").join(format!("hostile-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Triangle positions (36 bytes), u16 indices (6 + 2 padding), two key
/// times (8 bytes) and two translations (24 bytes).
fn bin(times: [f32; 2], values: [f32; 6]) -> Vec<u8> {
    let floats = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let mut b: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    b.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()));
    b.extend(times.iter().chain(&values).flat_map(|f| f.to_le_bytes()));
    b
}

/// A one-triangle glTF with an embedded buffer; `extra` adds top-level
/// members, `node_extra` members of node 0.
fn gltf(name: &str, data: &[u8], node_extra: &str, extra: &str) -> (PathBuf, String) {
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_ior", "KHR_materials_emissive_strength", "KHR_materials_transmission"],
  "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "name": "tri node"{node_extra}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "buffers": [{{"uri": "data:application/octet-stream;base64,{}", "byteLength": {}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 6}},
    {{"buffer": 0, "byteOffset": 44, "byteLength": 8}},
    {{"buffer": 0, "byteOffset": 52, "byteLength": 24}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}},
    {{"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR"}},
    {{"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}}
  ]{extra}}}"#,
        base64(data),
        data.len()
    );
    let path = temp_dir(name).join(format!("{name}.gltf"));
    std::fs::write(&path, &json).unwrap();
    (path, json)
}

fn load_error(path: &std::path::Path) -> String {
    match Scene::load(path) {
        Ok(_) => panic!("{} loaded but should have failed", path.display()),
        Err(e) => format!("{e:#}"),
    }
}

/// Loads `extra` (materials, lights, cameras) and expects an error naming
/// the file and every part of `expected`.
fn expect_error(name: &str, node_extra: &str, extra: &str, expected: &[&str]) {
    let (path, _) = gltf(name, &bin([0.0, 1.0], [0.0; 6]), node_extra, extra);
    let err = load_error(&path);
    assert!(err.contains(&format!("{name}.gltf")), "{name}: error does not name the file: {err}");
    for e in expected {
        assert!(err.contains(e), "{name}: error lacks '{e}': {err}");
    }
}

fn material(name: &str, json: &str, expected: &[&str]) {
    let extra = format!(r#", "materials": [{{"name": "m0"}}, {{"name": "glass", {json}}}]"#);
    let mut all = vec!["material 1 'glass'"];
    all.extend(expected);
    expect_error(name, "", &extra, &all);
}

#[test]
fn valid_file_loads() {
    let extra = r#", "materials": [{"name": "glass", "pbrMetallicRoughness": {"roughnessFactor": 0.1},
        "extensions": {"KHR_materials_ior": {"ior": 1.33}, "KHR_materials_transmission": {"transmissionFactor": 1}}}],
      "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100, "aspectRatio": 1.5}}],
      "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "intensity": 20, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}}]}}"#;
    let (path, _) = gltf(
        "valid",
        &bin([0.0, 1.0], [0.0; 6]),
        r#", "camera": 0, "extensions": {"KHR_lights_punctual": {"light": 0}}"#,
        extra,
    );
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.lights[0].intensity, 20.0);
}

#[test]
fn material_factors_out_of_range_are_errors() {
    let ior = |v: &str| format!(r#""extensions": {{"KHR_materials_ior": {{"ior": {v}}}}}"#);
    material("ior0", &ior("0"), &["ior 0 is out of range", "ior >= 1, or 0"]);
    material("ior_half", &ior("0.5"), &["ior 0.5 is out of range"]);
    material("rough", r#""pbrMetallicRoughness": {"roughnessFactor": -1}"#, &["roughnessFactor -1"]);
    material("metal", r#""pbrMetallicRoughness": {"metallicFactor": 2}"#, &["metallicFactor 2"]);
    material("base", r#""pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1.5]}"#, &["baseColorFactor"]);
    material("emissive", r#""emissiveFactor": [0, 3, 0]"#, &["emissiveFactor"]);
    material(
        "strength",
        r#""extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1e39}}"#,
        &["emissiveStrength inf"],
    );
    material(
        "strength_huge",
        r#""extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1e30}}"#,
        &["emissiveStrength"],
    );
    material(
        "transmission",
        r#""extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.5}}"#,
        &["transmissionFactor 1.5"],
    );
    material(
        "volume",
        r#""extensions": {"KHR_materials_volume": {"attenuationDistance": -2}}"#,
        &["attenuationDistance -2"],
    );
    material("cutoff", r#""alphaMode": "MASK", "alphaCutoff": -0.5"#, &["alphaCutoff -0.5"]);
}

fn light(name: &str, json: &str, expected: &[&str]) {
    let extra =
        format!(r#", "extensions": {{"KHR_lights_punctual": {{"lights": [{{"name": "lamp", {json}}}]}}}}"#);
    let mut all = vec!["light 0 'lamp'"];
    all.extend(expected);
    expect_error(name, r#", "extensions": {"KHR_lights_punctual": {"light": 0}}"#, &extra, &all);
}

#[test]
fn light_values_out_of_range_are_errors() {
    light("intensity_inf", r#""type": "point", "intensity": 1e39"#, &["intensity inf"]);
    light("intensity_huge", r#""type": "point", "intensity": 1e30"#, &["intensity"]);
    light("intensity_neg", r#""type": "point", "intensity": -1"#, &["intensity -1"]);
    light("color", r#""type": "point", "color": [1, 2, 1]"#, &["color"]);
    light("range", r#""type": "point", "range": 0"#, &["range 0"]);
    light(
        "cones",
        r#""type": "spot", "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.5}"#,
        &["innerConeAngle 0.6 must be smaller"],
    );
    light("outer", r#""type": "spot", "spot": {"outerConeAngle": 3}"#, &["outerConeAngle 3"]);
}

fn camera(name: &str, json: &str, expected: &[&str]) {
    let extra = format!(r#", "cameras": [{{"name": "cam", {json}}}]"#);
    let mut all = vec!["camera 0 'cam'"];
    all.extend(expected);
    expect_error(name, r#", "camera": 0"#, &extra, &all);
}

#[test]
fn camera_values_out_of_range_are_errors() {
    let p = |v: &str| format!(r#""type": "perspective", "perspective": {{{v}}}"#);
    camera("yfov", &p(r#""yfov": 0, "znear": 0.1"#), &["yfov 0"]);
    camera("yfov_inf", &p(r#""yfov": 1e39, "znear": 0.1"#), &["yfov inf"]);
    camera("znear", &p(r#""yfov": 1, "znear": -1"#), &["znear -1"]);
    camera("zfar", &p(r#""yfov": 1, "znear": 1, "zfar": 0.5"#), &["zfar 0.5"]);
    camera("aspect", &p(r#""yfov": 1, "znear": 1, "aspectRatio": 0"#), &["aspectRatio 0"]);
    camera(
        "ortho",
        r#""type": "orthographic", "orthographic": {"xmag": 0, "ymag": 1, "znear": 0, "zfar": 1}"#,
        &["xmag 0"],
    );
}

const ANIMATION: &str = r#", "animations": [{"name": "move",
    "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
    "samplers": [{"input": 2, "output": 3}]}]"#;

#[test]
fn non_finite_or_huge_keyframes_are_errors() {
    let cases: [(&str, [f32; 2], [f32; 6], &str); 5] = [
        ("time_nan", [0.0, f32::NAN], [0.0; 6], "not finite"),
        ("time_order", [1.0, 0.5], [0.0; 6], "not increasing"),
        ("value_nan", [0.0, 1.0], [0.0, f32::NAN, 0.0, 0.0, 0.0, 0.0], "value 0"),
        ("value_inf", [0.0, 1.0], [0.0, 0.0, 0.0, 0.0, f32::INFINITY, 0.0], "value 1"),
        ("value_huge", [0.0, 1.0], [0.0, 0.0, 0.0, 0.0, 1e31, 0.0], "1e30 or more"),
    ];
    for (name, times, values, expected) in cases {
        let (path, _) = gltf(name, &bin(times, values), "", ANIMATION);
        let err = load_error(&path);
        for e in [&format!("{name}.gltf"), "animation 'move' channel 0", expected] {
            assert!(err.contains(e), "{name}: error lacks '{e}': {err}");
        }
    }
}

#[test]
fn huge_node_translation_is_an_error() {
    let (path, _) = gltf("translation", &bin([0.0, 1.0], [0.0; 6]), r#", "translation": [0, 1e30, 0]"#, "");
    let err = load_error(&path);
    assert!(err.contains("translation.gltf") && err.contains("tri node") && err.contains("1e30"), "{err}");
}

/// A chain of `depth` nodes, each the only child of the next (children
/// come before their parents, so a walk in index order meets the leaf
/// first); node 0 is the leaf holding the triangle, the last node the root.
/// Each level moves 0.001 up.
fn chain(name: &str, depth: usize) -> PathBuf {
    let mut nodes = String::from(r#"{"mesh": 0, "name": "leaf", "translation": [0, 0.001, 0]}"#);
    for i in 1..depth {
        nodes.push_str(&format!(r#",{{"children": [{}], "translation": [0, 0.001, 0]}}"#, i - 1));
    }
    let (path, json) = gltf(name, &bin([0.0, 1.0], [0.0; 6]), "", "");
    let json = json
        .replace(r#""scenes": [{"nodes": [0]}]"#, &format!(r#""scenes": [{{"nodes": [{}]}}]"#, depth - 1));
    let start = json.find(r#""nodes": [{"mesh""#).unwrap();
    let end = start + json[start..].find("}],").unwrap() + 2;
    std::fs::write(&path, format!("{}\"nodes\": [{nodes}]{}", &json[..start], &json[end..])).unwrap();
    path
}

#[test]
fn deep_chain_loads_and_poses_on_a_small_stack() {
    const DEPTH: usize = 100_000;
    let path = chain("chain", DEPTH);
    // A recursive walk needs far more than 256 KiB for 100,000 levels.
    let worker = std::thread::Builder::new().stack_size(256 * 1024).spawn(move || {
        let mut scene = Scene::load(&path).unwrap();
        assert_eq!(scene.nodes.len(), DEPTH);
        let leaf = scene.world_matrices()[0].w_axis.y;
        assert!((leaf - 100.0).abs() < 0.1, "leaf at y = {leaf}");
        use hybrid_rt::scene::animation::{Animation, AnimationChannel, Channel, Interpolation};
        let lift = AnimationChannel {
            node: DEPTH - 1,
            times: vec![0.0, 1.0],
            interpolation: Interpolation::Linear,
            values: Channel::Translation(vec![glam::Vec3::ZERO, glam::Vec3::new(0.0, 0.0, 10.0)]),
        };
        scene.animations.push(Animation::new("lift".into(), vec![lift]));
        scene.animate(0, 0.5);
        let z = scene.instances[0].world.w_axis.z;
        assert!((z - 5.0).abs() < 1e-3, "posed leaf at z = {z}");
    });
    worker.unwrap().join().expect("loading or posing the deep chain failed");
}

#[test]
fn cycles_and_shared_children_are_rejected() {
    let cases = [
        ("self", r#"{"name": "a", "children": [0], "mesh": 0}"#, "node 'a' is its own ancestor"),
        (
            "loop",
            r#"{"name": "a", "children": [1], "mesh": 0}, {"name": "b", "children": [0]}"#,
            "is its own ancestor",
        ),
        (
            "shared",
            r#"{"name": "a", "children": [2], "mesh": 0}, {"name": "b", "children": [2]}, {"name": "c"}"#,
            "node 'c' has more than one parent",
        ),
    ];
    for (name, nodes, expected) in cases {
        let (path, json) = gltf(name, &bin([0.0, 1.0], [0.0; 6]), "", "");
        let json = json.replace(r#"{"mesh": 0, "name": "tri node"}"#, nodes);
        std::fs::write(&path, json).unwrap();
        let err = load_error(&path);
        assert!(err.contains(&format!("{name}.gltf")) && err.contains(expected), "{name}: {err}");
    }
}
