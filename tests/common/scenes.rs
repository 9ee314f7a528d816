//! Scene texts shared by the ray-tracing and backend tests: analytic
//! set-ups whose correct image is known in closed form.
#![allow(dead_code)]

use glam::{EulerRot, Quat, Vec3};

use super::toml::*;

/// A similarity transform applied to a whole scene:
/// x -> tilt(x * scale) + offset, `tilt_deg` in the scene files' convention
/// (about world X, then Y, then Z).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub scale: f32,
    pub offset: Vec3,
    pub tilt_deg: Vec3,
}

/// `[x, y, z]` with 10 significant digits.
fn sci3(v: Vec3) -> Raw {
    Raw(format!("[{:.9e}, {:.9e}, {:.9e}]", v.x, v.y, v.z))
}

impl Frame {
    pub const IDENTITY: Frame = Frame::at(1.0, Vec3::ZERO);
    pub const fn at(scale: f32, offset: Vec3) -> Frame {
        Frame { scale, offset, tilt_deg: Vec3::ZERO }
    }
    fn tilt(&self) -> Quat {
        let r = self.tilt_deg * (std::f32::consts::PI / 180.0);
        Quat::from_euler(EulerRot::ZYX, r.z, r.y, r.x)
    }
    fn p(&self, v: [f32; 3]) -> Raw {
        sci3(self.tilt() * (Vec3::from(v) * self.scale) + self.offset)
    }
    /// An object rotation `deg` (scene-file convention) composed with the tilt.
    fn r(&self, deg: [f32; 3]) -> Raw {
        let d = Vec3::from(deg) * (std::f32::consts::PI / 180.0);
        let q = self.tilt() * Quat::from_euler(EulerRot::ZYX, d.z, d.y, d.x);
        let (z, y, x) = q.to_euler(EulerRot::ZYX);
        sci3(Vec3::new(x.to_degrees(), y.to_degrees(), z.to_degrees()))
    }
    /// A direction: tilted, not scaled or moved.
    fn dir(&self, v: [f32; 3]) -> Raw {
        sci3(self.tilt() * Vec3::from(v))
    }
    fn s(&self, v: f32) -> Raw {
        Raw(format!("{:.9e}", v * self.scale))
    }
}

/// Ground plane, a point light at (0, 4, 0) and a 1 x 1 horizontal square
/// at height 2 with material `occluder` (a material named "occluder"): the
/// shadow is the square [-1, 1] x [-1, 1] on the ground.
pub fn shadow_scene(f: Frame, occluder: Block) -> String {
    let flat = f.r([0.0, 0.0, 0.0]);
    scene_toml([
        black_sky(),
        camera(f.p([2.5, 7.0, 2.5]), f.p([0.0, 0.0, 0.0]))
            .up(f.dir([0.0, 1.0, 0.0]))
            .yfov(60)
            .znear(f.s(0.05)),
        point(f.p([0.0, 4.0, 0.0]), Raw(format!("{:.9e}", 50.0 * f.scale * f.scale))),
        lambert("ground", [0.8, 0.8, 0.8]).metallic(0.0).ior(1.0),
        occluder,
        plane("ground", [f.s(40.0), f.s(40.0)]).at(f.p([0.0, 0.0, 0.0])).rot(flat.clone()).material("ground"),
        plane("occluder", [f.s(1.0), f.s(1.0)]).at(f.p([0.0, 2.0, 0.0])).rot(flat).material("occluder"),
    ])
}

/// A dark grey opaque square, as the shadow scene's occluder.
pub fn opaque_occluder() -> Block {
    lambert("occluder", [0.1, 0.1, 0.1]).double_sided()
}

/// A glass square (transmission 1) tinted `tint`, as the shadow scene's occluder.
pub fn glass_occluder(tint: [f32; 3]) -> Block {
    glass("occluder", 1.5).base(shown3(tint)).double_sided()
}

/// A metal mirror at z = 0 facing +z, an emissive wall at z = 6 facing it,
/// the camera in between looking at the mirror.
pub fn mirror_scene(f0: [f32; 3], wall: [f32; 3]) -> String {
    scene_toml([
        black_sky(),
        camera([0.0, 0.0, 3.0], [0.0, 0.0, 0.0]).yfov(40),
        no_light(),
        mirror("mirror", shown3(f0)),
        emitter("wall", shown3(wall)).roughness(1.0),
        plane("mirror", [4.0, 4.0]).rot([90.0, 0.0, 0.0]).material("mirror"),
        plane("wall", [40.0, 40.0]).at([0.0, 0.0, 6.0]).rot([-90.0, 0.0, 0.0]).material("wall"),
    ])
}

/// Two mirrors facing each other with a ball between them.
pub fn facing_mirrors() -> String {
    scene_toml([
        environment([0.3, 0.3, 0.3]),
        camera([0.3, 0.2, 1.5], [0.0, 0.0, -2.0]).yfov(60),
        point([0.0, 1.5, 0.0], 10.0),
        mirror("mirror", [0.98, 0.98, 0.98]),
        material("orange").base([1.0, 0.4, 0.0]),
        plane("front", [10.0, 10.0]).at([0.0, 0.0, -2.0]).rot([90.0, 0.0, 0.0]).material("mirror"),
        plane("back", [10.0, 10.0]).at([0.0, 0.0, 2.0]).rot([-90.0, 0.0, 0.0]).material("mirror"),
        sphere("ball", 0.3).at([0.0, -0.3, 0.0]).material("orange"),
    ])
}

/// Mirror ball, glass ball, box, ground; point, spot and directional lights.
pub fn agreement() -> String {
    scene_toml([
        environment([0.3, 0.4, 0.6]),
        camera([0.0, 2.5, 6.0], [0.0, 0.5, 0.0]).yfov(50),
        point([2.0, 5.0, 2.0], 60.0),
        spot([-3.0, 4.0, 1.0], [0.6, -0.8, -0.2], 80.0).cones(20, 35),
        directional([-0.3, -1.0, -0.5], 2.0),
        mirror("mirror", [0.9, 0.9, 0.9]),
        glass("glass", 1.5),
        material("red").base([0.8, 0.1, 0.1]).roughness(0.7),
        material("ground").base([0.7, 0.7, 0.7]).roughness(0.8),
        plane("ground", [20.0, 20.0]).material("ground"),
        sphere("mirror ball", 0.8).at([-1.2, 0.8, 0.0]).material("mirror"),
        sphere("glass ball", 0.8).at([1.2, 0.8, 0.5]).material("glass"),
        cube("box", 1.0).at([0.3, 0.5, -2.0]).rot([0.0, 30.0, 0.0]).material("red"),
    ])
}

/// A white 4x4 floor (4 vertices; tests/render/prt.rs subdivides it) under a
/// sphere of radius 1 centred at height 2; the camera looks at the origin
/// from the side, under the sphere. No light: the frame is the ambient
/// term. Under a constant environment L the unoccluded ambient irradiance
/// of a floor point at distance D from the centre is pi L (1 - r^2 d / D^3)
/// (pi L (1 - (r/d)^2) below the centre); the sphere's underside sees the
/// floor (tests/render/prt.rs, tests/report/prt_report.rs). White is pure
/// Lambert (IOR 1: no specular lobe), so the frame is the diffuse ambient alone.
pub fn plane_under_sphere() -> String {
    scene_toml([
        camera([3.0, 0.6, 0.0], [0.0, 0.0, 0.0]).yfov(60),
        no_light(),
        lambert("white", [0.8, 0.8, 0.8]).ior(1.0),
        plane("floor", [4.0, 4.0]).material("white"),
        sphere("ball", 1.0).slices(32, 16).at([0.0, 2.0, 0.0]).material("white"),
    ])
}

/// Writes a glTF file `file` (under the test tmpdir's `scenes/`) holding one
/// double-sided quad of half-size `half` in the XY plane facing +Z, uv
/// repeated `uv_repeat` times across it, with an alpha-masked (cutoff 0.5)
/// base-colour texture `texture`: a fence whose gaps show what is behind.
pub fn masked_quad_gltf(
    file: &str,
    half: f32,
    uv_repeat: f32,
    texture: &image::RgbaImage,
) -> std::path::PathBuf {
    let r = uv_repeat;
    let material = r#"{"name": "stripes", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": true,
    "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 1.0}}"#;
    quad_gltf(file, half, [[0.0, r], [r, r], [r, 0.0], [0.0, 0.0]], texture, material)
}

/// Writes a glTF file `file` (under the test tmpdir's `scenes/`) holding one
/// quad of half-size `half` in the XY plane facing +Z, corners (-,-), (+,-),
/// (+,+), (-,+) at `uvs`, with the material `material` (a glTF material
/// object whose textures are index 0: `texture`, mipmapped, repeating).
pub fn quad_gltf(
    file: &str,
    half: f32,
    uvs: [[f32; 2]; 4],
    texture: &image::RgbaImage,
    material: &str,
) -> std::path::PathBuf {
    let mut png = Vec::new();
    texture.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
    let mut bin: Vec<u8> = Vec::new();
    let s = half;
    let mut put = |v: &[f32]| bin.extend(v.iter().flat_map(|x| x.to_le_bytes()));
    for p in [[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0]] {
        put(&p);
    }
    for _ in 0..4 {
        put(&[0.0, 0.0, 1.0]);
    }
    for uv in uvs {
        put(&uv);
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_texture_transform"],
  "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "name": "quad"}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}, "indices": 3, "material": 0}}]}}],
  "materials": [{material}],
  "textures": [{{"source": 0, "sampler": 0}}],
  "samplers": [{{"wrapS": 10497, "wrapT": 10497, "minFilter": 9987, "magFilter": 9729}}],
  "images": [{{"uri": "data:image/png;base64,{png}"}}],
  "buffers": [{{"uri": "data:application/octet-stream;base64,{bin}", "byteLength": {len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 128, "byteLength": 12}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-{s}, -{s}, 0], "max": [{s}, {s}, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}}
  ]
}}"#,
        png = super::base64(&png),
        bin = super::base64(&bin),
        len = bin.len(),
    );
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scenes");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(file);
    std::fs::write(&path, json).unwrap();
    path
}
