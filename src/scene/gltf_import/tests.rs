//! Unit tests of the glTF importer: Khronos sample models, and small
//! generated files for each error and edge case.

use std::path::{Path, PathBuf};

use glam::Vec3;
use gltf::mesh::Mode;

use super::geometry::triangle_list;
use super::load;
use crate::scene::{AlphaMode, Filter, LightKind, SamplerDesc, Scene, TextureRef, UvTransform, Vertex, Wrap};

fn shared(relative: &str) -> PathBuf {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/assets")).join(relative);
    assert!(
        path.exists(),
        "missing shared test asset {} (CI keeps ../shared beside the checkout)",
        path.display()
    );
    path
}

/// An empty scratch directory for one test.
fn temp_dir(test: &str) -> PathBuf {
    // One fixed folder per test, emptied first: reruns do not pile up temp dirs.
    let dir = std::env::temp_dir().join("hybrid-rt-tests").join(format!("gltf-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("cannot create a temp dir");
    dir
}

fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let n = chunk.iter().enumerate().fold(0u32, |n, (i, &b)| n | (b as u32) << (16 - 8 * i));
        for i in 0..4 {
            let c = if i <= chunk.len() { ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char } else { '=' };
            out.push(c);
        }
    }
    out
}

/// 36 bytes of positions, 6 bytes of u16 indices (+2 padding), then 24
/// bytes of UVs equal to the positions' xy.
fn triangle_bin(positions: [[f32; 3]; 3], indices: [u16; 3]) -> Vec<u8> {
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    bin.extend([0, 0]);
    bin.extend(TRIANGLE.iter().flat_map(|p| p[..2].to_vec()).flat_map(|f| f.to_le_bytes()));
    bin
}

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// One indexed triangle mesh "tri" reading buffer `uri`; `extra` adds
/// top-level members (materials, textures, ...) and `material` makes the
/// primitive use material 0.
fn triangle_json(uri: &str, index_count: u32, material: bool, extra: &str) -> String {
    let material = if material { r#", "material": 0"# } else { "" };
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "name": "tri node"}}],
  "meshes": [{{"name": "tri", "primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 2}}, "indices": 1{material}}}]}}],
  "buffers": [{{"uri": "{uri}", "byteLength": 68}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 6}},
    {{"buffer": 0, "byteOffset": 44, "byteLength": 24}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": {index_count}, "type": "SCALAR"}},
    {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}}
  ]{extra}
}}"#
    )
}

/// Writes `tri.gltf` + `tri.bin` and returns the .gltf path.
fn write_triangle(dir: &Path, bin: &[u8], json: &str) -> PathBuf {
    std::fs::write(dir.join("tri.bin"), bin).unwrap();
    let path = dir.join("tri.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn error_of(path: &Path) -> String {
    match load(path) {
        Ok(_) => panic!("{} loaded but should have failed", path.display()),
        Err(e) => format!("{e:#}"),
    }
}

fn assert_orthonormal_frame(v: &Vertex) {
    let n = Vec3::from(v.normal);
    let t = Vec3::from_slice(&v.tangent[..3]);
    assert!((n.length() - 1.0).abs() < 1e-3 && (t.length() - 1.0).abs() < 1e-3, "{v:?}");
    assert!(n.dot(t).abs() < 1e-3, "{v:?}");
    assert_eq!(v.tangent[3].abs(), 1.0);
}

#[test]
fn khronos_triangle_gets_flat_normals_and_a_default_material() {
    let scene = load(&shared("gltf/Triangle/glTF/Triangle.gltf")).unwrap();
    assert_eq!(scene.meshes.len(), 1);
    let p = &scene.meshes[0].primitives[0];
    assert_eq!(p.indices, vec![0, 1, 2]);
    assert!(p.vertices.iter().all(|v| v.normal == [0.0, 0.0, 1.0] && v.uv == [0.0, 0.0]));
    assert!(p.vertices.iter().all(|v| v.tangent[3] == 1.0), "fallback tangents have w = 1");
    p.vertices.iter().for_each(assert_orthonormal_frame);
    assert_eq!(scene.materials.len(), 1, "the default material is appended");
    assert_eq!(p.material, 0);
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.nodes[0].object, Some(0));
    assert_eq!(scene.roots, vec![0]);
    assert_eq!(p.bounds.max, Vec3::new(1.0, 1.0, 0.0));
}

#[test]
fn embedded_and_external_buffers_match() {
    let external = load(&shared("gltf/Triangle/glTF/Triangle.gltf")).unwrap();
    let embedded = load(&shared("gltf/Triangle/glTF-Embedded/Triangle.gltf")).unwrap();
    let (a, b) = (&external.meshes[0].primitives[0], &embedded.meshes[0].primitives[0]);
    assert_eq!(a.vertices, b.vertices);
    assert_eq!(a.indices, b.indices);
}

#[test]
fn non_indexed_triangle_gets_sequential_indices() {
    let scene = load(&shared("gltf/TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf")).unwrap();
    assert_eq!(scene.meshes[0].primitives[0].indices, vec![0, 1, 2]);
}

#[test]
fn damaged_helmet_textures_and_generated_tangents() {
    let scene = load(&shared("gltf/DamagedHelmet/glTF/DamagedHelmet.gltf")).unwrap();
    let p = &scene.meshes[0].primitives[0];
    let m = &scene.materials[p.material];
    let tex = |r: Option<TextureRef>| &scene.textures[r.expect("texture slot is empty").texture];
    assert!(tex(m.base_color_texture).srgb);
    assert!(tex(m.emissive_texture).srgb);
    assert!(!tex(m.normal_texture).srgb);
    assert!(!tex(m.metallic_roughness_texture).srgb);
    assert!(!tex(m.occlusion_texture).srgb);
    assert_eq!(scene.textures.len(), 5);
    for t in &scene.textures {
        assert_eq!(t.rgba8.len(), (t.width * t.height * 4) as usize);
    }
    assert!(m.emissive.iter().all(|&e| e > 0.0));
    // The file has no TANGENT attribute: they must have been generated.
    p.vertices.iter().for_each(assert_orthonormal_frame);
    let distinct: std::collections::HashSet<[u32; 3]> = p
        .vertices
        .iter()
        .map(|v| v.tangent[..3].iter().map(|f| f.to_bits()).collect::<Vec<_>>().try_into().unwrap())
        .collect();
    assert!(distinct.len() > 100, "tangents look like a constant fallback");
}

#[test]
fn sponza_is_large_and_instanced() {
    let scene = Scene::load(&shared("scenes/SponzaCapsaicin/Sponza.gltf")).unwrap();
    assert!(scene.triangle_count() > 100_000, "{} triangles", scene.triangle_count());
    assert_eq!(scene.objects.len(), scene.nodes.iter().filter(|n| n.mesh.is_some()).count());
    assert!(scene.textures.len() >= 49);
    assert!(scene.materials.iter().any(|m| m.alpha_mode == AlphaMode::Blend));
    // Normal-mapped primitives had no TANGENT attribute: generated ones.
    let mapped = scene.meshes.iter().flat_map(|m| &m.primitives);
    let mapped = mapped.filter(|p| scene.materials[p.material].normal_texture.is_some());
    mapped.flat_map(|p| &p.vertices).step_by(97).for_each(assert_orthonormal_frame);
    let extent = scene.bounds.extent();
    assert!(extent.x > 20.0 && extent.y > 10.0, "Sponza bounds {:?}", scene.bounds);
}

#[test]
fn lights_and_cameras_are_placed_in_world_space() {
    let dir = temp_dir("lights");
    let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let json = triangle_json(&uri, 3, false, "").replace(
        r#""nodes": [{"mesh": 0, "name": "tri node"}],"#,
        r#""nodes": [
                {"mesh": 0, "name": "tri node", "children": [1, 2, 3]},
                {"name": "lamp", "translation": [0, 2, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                {"name": "spot", "translation": [1, 0, 0], "rotation": [-0.7071068, 0, 0, 0.7071068],
                 "extensions": {"KHR_lights_punctual": {"light": 1}}},
                {"name": "eye", "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1], "camera": 0}
            ],
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "point", "color": [1, 0.5, 0.25], "intensity": 20, "range": 8},
                {"type": "spot", "name": "beam", "intensity": 5, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}
            ]}},
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],"#,
    );
    let path = dir.join("lights.gltf");
    std::fs::write(&path, json).unwrap();
    let mut scene = load(&path).unwrap();
    // Moving the root must move its children's world transforms.
    scene.nodes[0].local.translation = glam::DVec3::new(10.0, 0.0, 0.0);
    assert_eq!(scene.lights.len(), 2);
    let point = &scene.lights[0];
    assert_eq!(point.kind, LightKind::Point);
    assert_eq!(point.position, glam::DVec3::new(0.0, 2.0, 0.0));
    assert_eq!(point.color, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!((point.intensity, point.range, point.node), (20.0, Some(8.0), Some(1)));
    let spot = &scene.lights[1];
    assert_eq!(spot.name, "beam");
    assert_eq!(spot.kind, LightKind::Spot { inner_cone: 0.2, outer_cone: 0.5 });
    // -90 degrees about X turns the spot's -Z into -Y.
    assert!((spot.direction - Vec3::NEG_Y).length() < 1e-5, "{}", spot.direction);
    assert_eq!(spot.position, glam::DVec3::new(1.0, 0.0, 0.0));
    assert_eq!(scene.cameras.len(), 1);
    let cam = &scene.cameras[0];
    assert_eq!((cam.yfov, cam.znear), (0.8, 0.1));
    assert_eq!(cam.position(), Vec3::new(0.0, 0.0, 5.0));
    assert_eq!(scene.nodes[3].camera, Some(0));
    assert_eq!(scene.nodes[3].parent, Some(0));
    assert_eq!(scene.world_matrices()[3].w_axis.truncate(), glam::DVec3::new(10.0, 0.0, 5.0));
}

#[test]
fn textures_are_deduplicated_per_image_sampler_and_colour_space() {
    let dir = temp_dir("textures");
    // A 16-bit greyscale PNG exercises the format conversion to RGBA8.
    let grey =
        image::ImageBuffer::<image::Luma<u16>, _>::from_fn(2, 2, |x, _| image::Luma([x as u16 * 65535]));
    grey.save(dir.join("grey.png")).unwrap();
    let extra = r#",
  "materials": [
    {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 0}},
     "emissiveTexture": {"index": 1}, "normalTexture": {"index": 0, "scale": 0.5}}
  ],
  "samplers": [{"magFilter": 9728, "minFilter": 9729, "wrapS": 33071, "wrapT": 33648}],
  "textures": [{"source": 0, "sampler": 0}, {"source": 0, "sampler": 0}],
  "images": [{"uri": "grey.png"}]"#;
    let path =
        write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &triangle_json("tri.bin", 3, true, extra));
    let scene = load(&path).unwrap();
    // (grey, sampler, sRGB) for base colour and emissive; (grey, sampler, linear) for the rest.
    assert_eq!(scene.textures.len(), 2);
    let m = &scene.materials[0];
    assert_eq!(m.base_color_texture, m.emissive_texture);
    assert_eq!(m.metallic_roughness_texture, m.normal_texture);
    assert_ne!(m.base_color_texture, m.normal_texture);
    assert_eq!(m.normal_scale, 0.5);
    let t = &scene.textures[0];
    assert_eq!(t.rgba8, vec![0, 0, 0, 255, 255, 255, 255, 255, 0, 0, 0, 255, 255, 255, 255, 255]);
    assert_eq!(
        t.sampler,
        SamplerDesc {
            mag_filter: Filter::Nearest,
            min_filter: Filter::Linear,
            mipmaps: false,
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::MirroredRepeat
        }
    );
    // A normal-mapped material without TANGENT gets generated tangents.
    let p = &scene.meshes[0].primitives[0];
    assert!(p.vertices.iter().all(|v| v.tangent == [1.0, 0.0, 0.0, 1.0]), "{:?}", p.vertices);
}

/// A scratch directory holding `white.png` (2 x 2), for files that need a texture.
fn white_png_dir(test: &str) -> PathBuf {
    let dir = temp_dir(test);
    image::RgbaImage::from_pixel(2, 2, image::Rgba([255; 4])).save(dir.join("white.png")).unwrap();
    dir
}

/// KHR_texture_transform's example (the lower-left quadrant of the image,
/// turned): the spec's matrix T * R * S applied to the quad's corners.
#[test]
fn texture_transform_follows_the_spec_example() {
    let t = UvTransform::from_gltf([0.0, 1.0], std::f32::consts::FRAC_PI_2, [0.5, 0.5]);
    let corners = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]].map(|uv| t.apply(uv));
    let want = [[0.0, 1.0], [0.0, 0.5], [0.5, 1.0], [0.5, 0.5]];
    for (got, want) in corners.iter().zip(want) {
        assert!((got[0] - want[0]).abs() < 1e-6 && (got[1] - want[1]).abs() < 1e-6, "{corners:?}");
    }
    assert_eq!(UvTransform::default().apply([0.25, 0.75]), [0.25, 0.75]);
    // Scale, then rotation, then offset, by hand: (1, 0) -> (2 cos r, -2 sin r) + offset, (0, 1) -> (3 sin r,
    // 3 cos r) + offset.
    let (r, offset) = (0.3f32, [0.1, 0.2]);
    let t = UvTransform::from_gltf(offset, r, [2.0, 3.0]);
    let close = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6;
    assert!(close(t.apply([1.0, 0.0]), [2.0 * r.cos() + 0.1, -2.0 * r.sin() + 0.2]), "{t:?}");
    assert!(close(t.apply([0.0, 1.0]), [3.0 * r.sin() + 0.1, 3.0 * r.cos() + 0.2]), "{t:?}");
}

/// Each texture reference keeps its own transform (textureInfo through the
/// crate, normal and occlusion references from their raw JSON); texCoord in
/// the extension overrides the reference's; a non-number is an error naming
/// the material and the reference.
#[test]
fn texture_transforms_are_read_per_reference() {
    let dir = white_png_dir("texture-transform");
    let material = |normal_transform: &str| {
        format!(
            r#",
  "extensionsUsed": ["KHR_texture_transform"],
  "materials": [{{"name": "tiled",
    "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0,
      "extensions": {{"KHR_texture_transform": {{"offset": [0.5, 0.25], "scale": [2, 3]}}}}}}}},
    "normalTexture": {{"index": 0, "extensions": {{"KHR_texture_transform": {normal_transform}}}}},
    "occlusionTexture": {{"index": 0, "texCoord": 1, "extensions": {{"KHR_texture_transform": {{"texCoord": 0}}}}}},
    "emissiveTexture": {{"index": 0}}}}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "white.png"}}]"#
        )
    };
    let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
    let path =
        write_triangle(&dir, &bin, &triangle_json("tri.bin", 3, true, &material(r#"{"rotation": 1.0}"#)));
    let scene = load(&path).unwrap();
    let m = &scene.materials[0];
    let transform = |t: Option<TextureRef>| t.unwrap().transform;
    assert_eq!(transform(m.base_color_texture), UvTransform::from_gltf([0.5, 0.25], 0.0, [2.0, 3.0]));
    assert_eq!(transform(m.normal_texture), UvTransform::from_gltf([0.0; 2], 1.0, [1.0; 2]));
    assert_eq!(transform(m.occlusion_texture), UvTransform::IDENTITY);
    assert_eq!(m.occlusion_texture.unwrap().tex_coord, 0, "the extension's texCoord overrides");
    assert_eq!(transform(m.emissive_texture), UvTransform::IDENTITY);

    let bad = triangle_json("tri.bin", 3, true, &material(r#"{"rotation": "left"}"#));
    let err = error_of(&write_triangle(&dir, &bin, &bad));
    assert!(err.contains("material 0 'tiled'") && err.contains("normalTexture"), "{err}");
    assert!(err.contains("KHR_texture_transform"), "{err}");
    let huge = triangle_json("tri.bin", 3, true, &material(r#"{"scale": [1e38, 1]}"#));
    let err = error_of(&write_triangle(&dir, &bin, &huge));
    assert!(err.contains("normalTexture") && err.contains("must be finite"), "{err}");
}

/// KHR_materials_specular: factors, the weight texture (linear, A) and the
/// colour texture (sRGB); an out-of-range weight is an error naming it.
#[test]
fn specular_extension_is_read() {
    let dir = white_png_dir("specular");
    let material = |factor: &str| {
        format!(
            r#",
  "extensionsUsed": ["KHR_materials_specular"],
  "materials": [{{"name": "coated", "extensions": {{"KHR_materials_specular": {{"specularFactor": {factor},
    "specularColorFactor": [2, 1, 0.5], "specularTexture": {{"index": 0}}, "specularColorTexture": {{"index": 0}}}}}}}}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "white.png"}}]"#
        )
    };
    let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
    let scene =
        load(&write_triangle(&dir, &bin, &triangle_json("tri.bin", 3, true, &material("0.25")))).unwrap();
    let m = &scene.materials[0];
    assert_eq!((m.specular, m.specular_color), (0.25, [2.0, 1.0, 0.5]));
    let tex = |t: Option<TextureRef>| &scene.textures[t.unwrap().texture];
    assert!(!tex(m.specular_texture).srgb && tex(m.specular_color_texture).srgb);
    assert_eq!(crate::scene::Material::default().specular, 1.0, "no extension: the IOR's reflection");

    let err = error_of(&write_triangle(&dir, &bin, &triangle_json("tri.bin", 3, true, &material("1.5"))));
    assert!(err.contains("material 0 'coated'") && err.contains("specularFactor 1.5"), "{err}");
}

/// KHR_materials_clearcoat (raw JSON): factors, its three textures slotted linear with their transforms
/// and the normal map's scale, tangents generated for the coat's normal map; out-of-range factors and
/// dangling texture indices are errors naming the material and member.
#[test]
fn clearcoat_extension_is_read() {
    let dir = white_png_dir("clearcoat");
    let material = |members: &str| {
        format!(
            r#",
  "extensionsUsed": ["KHR_materials_clearcoat"],
  "materials": [{{"name": "paint", "extensions": {{"KHR_materials_clearcoat": {{{members}}}}}}}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "white.png"}}]"#
        )
    };
    let full = r#""clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.25,
    "clearcoatTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}},
    "clearcoatRoughnessTexture": {"index": 0},
    "clearcoatNormalTexture": {"index": 0, "scale": 0.5, "extensions": {"KHR_texture_transform": {"rotation": 1.0}}}"#;
    let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
    let load_with = |members: &str| {
        load(&write_triangle(&dir, &bin, &triangle_json("tri.bin", 3, true, &material(members))))
    };
    let scene = load_with(full).unwrap();
    let c = &scene.materials[0].clearcoat;
    assert_eq!((c.factor, c.roughness, c.normal_scale), (0.75, 0.25, 0.5));
    let tex = |t: Option<TextureRef>| t.unwrap();
    assert_eq!(tex(c.texture).transform, UvTransform::from_gltf([0.0; 2], 0.0, [2.0, 2.0]));
    assert_eq!(tex(c.roughness_texture).transform, UvTransform::IDENTITY);
    assert_eq!(tex(c.normal_texture).transform, UvTransform::from_gltf([0.0; 2], 1.0, [1.0; 2]));
    assert!([c.texture, c.roughness_texture, c.normal_texture]
        .iter()
        .all(|&t| !scene.textures[tex(t).texture].srgb));
    // Tangents generated from the UVs for the coat's normal map, as for a base normal map (not the
    // fallback frame).
    let tangents = |scene: &crate::scene::Scene| {
        scene.meshes[0].primitives[0].vertices.iter().map(|v| v.tangent).collect::<Vec<_>>()
    };
    let plain = load_with(r#""clearcoatFactor": 1"#).unwrap();
    let json = triangle_json("tri.bin", 3, true, &material(r#""clearcoatFactor": 1"#))
        .replace(r#""name": "paint","#, r#""name": "paint", "normalTexture": {"index": 0},"#);
    let base_mapped = load(&write_triangle(&dir, &bin, &json)).unwrap();
    assert_eq!(tangents(&scene), tangents(&base_mapped), "tangents for the coat's normal map");
    assert_ne!(tangents(&plain), tangents(&base_mapped), "UV tangents differ from the fallback here");
    // Members left out take the extension's defaults.
    let c = load_with(r#""clearcoatFactor": 1"#).unwrap().materials[0].clearcoat.clone();
    assert_eq!(c, crate::scene::Clearcoat { factor: 1.0, ..Default::default() });
    assert_eq!(crate::scene::Material::default().clearcoat.factor, 0.0, "no extension: no coat");

    for (members, expected) in [
        (r#""clearcoatFactor": 1.5"#, "clearcoatFactor 1.5"),
        (r#""clearcoatRoughnessFactor": -1"#, "clearcoatRoughnessFactor -1"),
        (r#""clearcoatTexture": {"index": 3}"#, "clearcoatTexture refers to texture 3"),
        (r#""clearcoatNormalTexture": {"index": 7}"#, "clearcoatNormalTexture refers to texture 7"),
        (r#""clearcoatFactor": "thick""#, "malformed KHR_materials_clearcoat"),
    ] {
        let err =
            error_of(&write_triangle(&dir, &bin, &triangle_json("tri.bin", 3, true, &material(members))));
        assert!(err.contains("material 0 'paint'") && err.contains(expected), "{members}: {err}");
    }
}

#[test]
fn strips_and_fans_become_lists() {
    assert_eq!(triangle_list(Mode::TriangleStrip, vec![0, 1, 2, 3, 4]), vec![0, 1, 2, 1, 3, 2, 2, 3, 4]);
    assert_eq!(triangle_list(Mode::TriangleFan, vec![0, 1, 2, 3]), vec![1, 2, 0, 2, 3, 0]);
    assert_eq!(triangle_list(Mode::Triangles, vec![0, 1, 2, 3]), vec![0, 1, 2]);
}

#[test]
fn glb_loads_and_truncated_glb_fails() {
    let dir = temp_dir("glb");
    let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
    let json = triangle_json("", 3, false, "").replace(r#""uri": "", "#, "");
    let bytes = glb(&json, &bin);
    let path = dir.join("tri.glb");
    std::fs::write(&path, &bytes).unwrap();
    let scene = load(&path).unwrap();
    assert_eq!(scene.meshes[0].primitives[0].indices, vec![0, 1, 2]);
    for cut in [bytes.len() - 10, 30, 14] {
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let err = error_of(&path);
        assert!(err.contains("tri.glb") && err.contains("truncated"), "{err}");
    }
}

#[test]
fn missing_files_are_named() {
    let err = error_of(Path::new("/nonexistent/scene.gltf"));
    assert!(err.contains("/nonexistent/scene.gltf"), "{err}");

    let dir = temp_dir("missing");
    let path = dir.join("tri.gltf");
    std::fs::write(&path, triangle_json("absent.bin", 3, false, "")).unwrap();
    let err = error_of(&path);
    assert!(err.contains("tri.gltf") && err.contains("buffer 0") && err.contains("absent.bin"), "{err}");

    let extra = r#",
  "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}],
  "images": [{"uri": "no%20such.png"}]"#;
    let path =
        write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &triangle_json("tri.bin", 3, true, extra));
    let err = error_of(&path);
    assert!(err.contains("tri.gltf") && err.contains("no such.png"), "{err}");
}

/// SimpleSkin with its JSON edited by `edit`, beside copies of its buffers.
fn edited_simple_skin(test: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let src = shared("gltf/SimpleSkin/glTF");
    let dir = temp_dir(test);
    for f in ["skinGeometry.bin", "skinningData.bin", "inverseBindMatrices.bin", "skinAnimation.bin"] {
        std::fs::copy(src.join(f), dir.join(f)).unwrap();
    }
    let json = std::fs::read_to_string(src.join("SimpleSkin.gltf")).unwrap();
    let path = dir.join("SimpleSkin.gltf");
    std::fs::write(&path, edit(&json)).unwrap();
    path
}

#[test]
fn skins_and_weights_are_imported() {
    let mut scene = load(&shared("gltf/SimpleSkin/glTF/SimpleSkin.gltf")).unwrap();
    scene.update_world();
    assert_eq!(scene.skins.len(), 1);
    assert_eq!(scene.skins[0].joints, vec![1, 2]);
    assert_eq!(scene.nodes[0].skin, Some(0));
    let w = scene.meshes[0].primitives[0].skin.as_ref().expect("JOINTS_0/WEIGHTS_0 read");
    assert_eq!(w.joints.len(), scene.meshes[0].primitives[0].vertices.len());
    for ws in &w.weights {
        assert!((ws.iter().sum::<f32>() - 1.0).abs() < 1e-5);
    }
    let inst = &scene.instances[0];
    assert_eq!(inst.skinned, Some(0));
    for model in [
        "gltf/Fox/glTF/Fox.gltf",
        "gltf/CesiumMan/glTF/CesiumMan.gltf",
        "gltf/RiggedFigure/glTF/RiggedFigure.gltf",
    ] {
        let mut s = load(&shared(model)).unwrap();
        s.update_world();
        assert!(s.instances.iter().any(|i| i.skinned.is_some()), "{model}: nothing skinned");
    }
}

#[test]
fn out_of_range_joint_is_rejected() {
    // Only one joint left while the weights still reference joint 1.
    let path = edited_simple_skin("bad-joint", |j| j.replace("\"joints\" : [ 1, 2 ]", "\"joints\" : [ 1 ]"));
    let err = error_of(&path);
    assert!(err.contains("uses joint 1") && err.contains("has 1 joints"), "{err}");
    assert!(err.contains("SimpleSkin.gltf"), "{err}");
}

#[test]
fn joints_without_weights_are_rejected() {
    let path = edited_simple_skin("no-weights", |j| j.replace(",\n        \"WEIGHTS_0\" : 3", ""));
    let err = error_of(&path);
    assert!(err.contains("JOINTS_0 but no WEIGHTS_0"), "{err}");
}

#[test]
fn non_finite_position_is_rejected() {
    let dir = temp_dir("nan");
    let mut positions = TRIANGLE;
    positions[1][2] = f32::NAN;
    let path =
        write_triangle(&dir, &triangle_bin(positions, [0, 1, 2]), &triangle_json("tri.bin", 3, false, ""));
    let err = error_of(&path);
    assert!(err.contains("tri.gltf: mesh 'tri' primitive 0: vertex 1 has a non-finite position"), "{err}");
}

#[test]
fn out_of_range_index_is_rejected() {
    let dir = temp_dir("index");
    let path =
        write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 7]), &triangle_json("tri.bin", 3, false, ""));
    let err = error_of(&path);
    assert!(err.contains("mesh 'tri' primitive 0") && err.contains("index 7"), "{err}");
}

#[test]
fn accessor_outside_its_buffer_view_is_rejected() {
    let dir = temp_dir("accessor");
    let path =
        write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &triangle_json("tri.bin", 30, false, ""));
    let err = error_of(&path);
    assert!(
        err.contains("tri.gltf") && err.contains("indices accessor 1") && err.contains("out of range"),
        "{err}"
    );
}

#[test]
fn corrupted_glb_bytes_never_panic() {
    let dir = temp_dir("corrupt");
    let json = triangle_json("", 3, false, "").replace(r#""uri": "", "#, "");
    let bytes = glb(&json, &triangle_bin(TRIANGLE, [0, 1, 2]));
    let path = dir.join("tri.glb");
    for i in 0..bytes.len() {
        for value in [0x00, 0x39, 0xff] {
            let mut corrupt = bytes.clone();
            corrupt[i] = value;
            std::fs::write(&path, &corrupt).unwrap();
            // Errors are fine; a panic fails the test.
            let _ = load(&path);
        }
    }
}

#[test]
fn odd_numbers_in_the_json_never_panic() {
    let dir = temp_dir("numbers");
    let extra = r#",
  "materials": [{"normalTexture": {"index": 0, "texCoord": 0}}],
  "textures": [{"source": 0, "sampler": 0}],
  "samplers": [{"minFilter": 9729, "wrapS": 10497}],
  "images": [{"bufferView": 2, "mimeType": "image/png"}]"#;
    let json = triangle_json("tri.bin", 3, true, extra);
    let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
    // Every run of digits, in turn, replaced by edge-case values.
    let runs: Vec<(usize, usize)> = json
        .char_indices()
        .filter(|&(i, c)| c.is_ascii_digit() && !json[..i].ends_with(|p: char| p.is_ascii_digit()))
        .map(|(i, _)| (i, json[i..].find(|c: char| !c.is_ascii_digit()).map_or(json.len(), |n| i + n)))
        .collect();
    assert!(runs.len() > 40);
    for (start, end) in runs {
        for value in ["0", "1", "2", "7", "65535", "4294967295", "18446744073709551615", "1e30"] {
            let mutated = format!("{}{value}{}", &json[..start], &json[end..]);
            let path = write_triangle(&dir, &bin, &mutated);
            // Errors are fine; a panic fails the test.
            let _ = load(&path);
        }
    }
}

#[test]
fn dangling_light_reference_is_an_error() {
    let dir = temp_dir("dangling");
    let json = triangle_json("tri.bin", 3, false, "").replace(
        r#"{"mesh": 0, "name": "tri node"}"#,
        r#"{"mesh": 0, "name": "tri node", "extensions": {"KHR_lights_punctual": {"light": 3}}}"#,
    );
    let path = write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &json);
    let err = error_of(&path);
    assert!(err.contains("tri.gltf") && err.contains("light"), "{err}");
}

/// The triangle plus a SCALAR accessor 3 over the UVs (0, 0, 1) for key
/// times and an animation 'slide' whose channels are `channels`.
fn animated_triangle(dir: &Path, channels: &str, samplers: &str) -> PathBuf {
    let extra = format!(
        r#", "animations": [{{"name": "slide", "channels": [{channels}], "samplers": [{samplers}]}}]"#
    );
    let json = triangle_json("tri.bin", 3, false, &extra).replace(
        r#""count": 3, "type": "VEC2"}"#,
        r#""count": 3, "type": "VEC2"}, {"bufferView": 2, "componentType": 5126, "count": 3, "type": "SCALAR"}"#,
    );
    write_triangle(dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &json)
}

#[test]
fn animations_are_imported_and_morph_channels_skipped() {
    use crate::scene::animation::{Channel, Interpolation};
    let dir = temp_dir("animation");
    let path = animated_triangle(
        &dir,
        r#"{"sampler": 0, "target": {"node": 0, "path": "translation"}},
               {"sampler": 1, "target": {"node": 0, "path": "weights"}}"#,
        r#"{"input": 3, "output": 0, "interpolation": "STEP"}, {"input": 3, "output": 3}"#,
    );
    let mut scene = load(&path).unwrap();
    assert_eq!(scene.animations.len(), 1);
    let a = &scene.animations[0];
    assert_eq!((a.name.as_str(), a.duration, a.channels.len()), ("slide", 1.0, 1));
    let c = &a.channels[0];
    assert_eq!((c.node, c.interpolation, &c.times), (0, Interpolation::Step, &vec![0.0, 0.0, 1.0]));
    assert_eq!(c.values, Channel::Translation(TRIANGLE.iter().map(|&p| Vec3::from(p)).collect()));
    scene.animate(0, 0.5);
    assert_eq!(scene.nodes[0].local.translation, glam::DVec3::new(1.0, 0.0, 0.0));
}

#[test]
fn malformed_animations_are_reported_with_the_file_and_channel() {
    let dir = temp_dir("bad-animation");
    let translation = r#"{"sampler": 0, "target": {"node": 0, "path": "translation"}}"#;
    let rotation = r#"{"sampler": 0, "target": {"node": 0, "path": "rotation"}}"#;
    let cases = [
        // VEC2 output for a translation.
        (translation, r#"{"input": 3, "output": 2}"#, "animation output accessor 2"),
        // Three values for three keys is not enough for a cubic spline.
        (translation, r#"{"input": 3, "output": 0, "interpolation": "CUBICSPLINE"}"#, "needs 9"),
        // VEC3 output for a rotation.
        (rotation, r#"{"input": 3, "output": 0}"#, "Vec4"),
        // VEC3 key times.
        (translation, r#"{"input": 0, "output": 0}"#, "animation input accessor 0"),
    ];
    for (channel, sampler, expected) in cases {
        let path = animated_triangle(&dir, channel, sampler);
        let err = error_of(&path);
        assert!(
            err.contains("tri.gltf") && err.contains("animation 'slide' channel 0") && err.contains(expected),
            "{sampler}: {err}"
        );
    }
    // Out-of-range accessor, sampler and node references never panic.
    for (channel, sampler) in [
        (translation, r#"{"input": 9, "output": 0}"#),
        (r#"{"sampler": 4, "target": {"node": 0, "path": "translation"}}"#, r#"{"input": 3, "output": 0}"#),
        (r#"{"sampler": 0, "target": {"node": 7, "path": "translation"}}"#, r#"{"input": 3, "output": 0}"#),
        (r#"{"sampler": 0, "target": {"node": 0, "path": "colour"}}"#, r#"{"input": 3, "output": 0}"#),
    ] {
        let err = error_of(&animated_triangle(&dir, channel, sampler));
        assert!(err.contains("tri.gltf"), "{err}");
    }
    // Every number of a valid animation, in turn, replaced by edge cases.
    let (channel, sampler) = (rotation, r#"{"input": 3, "output": 0, "interpolation": "CUBICSPLINE"}"#);
    let text = format!("{channel}|{sampler}");
    for (i, _) in text.char_indices().filter(|(_, c)| c.is_ascii_digit()) {
        for value in ["1", "2", "4", "9", "4294967295"] {
            let mutated = format!("{}{value}{}", &text[..i], &text[i + 1..]);
            let (c, s) = mutated.split_once('|').unwrap();
            // Errors are fine; a panic fails the test.
            let _ = load(&animated_triangle(&dir, c, s));
        }
    }
}

#[test]
fn invalid_json_references_are_reported_with_the_file() {
    let dir = temp_dir("invalid");
    let json = triangle_json("tri.bin", 3, false, "").replace(r#""indices": 1"#, r#""indices": 9"#);
    let path = write_triangle(&dir, &triangle_bin(TRIANGLE, [0, 1, 2]), &json);
    let err = error_of(&path);
    assert!(err.contains("tri.gltf") && err.contains("indices"), "{err}");
}

#[test]
fn node_extras_set_the_budget_relevance_and_cost() {
    let dir = temp_dir("extras");
    let bin = triangle_bin(TRIANGLE, [0, 1, 2]);
    let json = triangle_json("tri.bin", 3, false, "").replace(
        r#""name": "tri node"}"#,
        r#""name": "tri node", "extras": {"relevance": 0.5, "cost": 3, "author": "x"}}"#,
    );
    let scene = load(&write_triangle(&dir, &bin, &json)).unwrap();
    assert_eq!((scene.objects[0].props.relevance, scene.objects[0].props.cost), (0.5, 3.0));
    let plain = load(&write_triangle(&dir, &bin, &triangle_json("tri.bin", 3, false, ""))).unwrap();
    assert_eq!((plain.objects[0].props.relevance, plain.objects[0].props.cost), (1.0, 1.0));
    for bad in [r#""cost": -1"#, r#""cost": "high""#] {
        let e = error_of(&write_triangle(&dir, &bin, &json.replace(r#""cost": 3"#, bad)));
        assert!(e.contains("tri.gltf") && e.contains("tri node") && e.contains("extras.cost"), "{e}");
    }
}
