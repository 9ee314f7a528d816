//! Scene texts shared by the ray-tracing and backend tests: analytic
//! set-ups whose correct image is known in closed form.
#![allow(dead_code)]

use glam::{EulerRot, Quat, Vec3};

/// A similarity transform applied to a whole scene:
/// x -> tilt(x * scale) + offset, `tilt_deg` in the scene files' convention
/// (about world X, then Y, then Z).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub scale: f32,
    pub offset: Vec3,
    pub tilt_deg: Vec3,
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
    fn p(&self, v: [f32; 3]) -> String {
        let v = self.tilt() * (Vec3::from(v) * self.scale) + self.offset;
        format!("[{:.9e}, {:.9e}, {:.9e}]", v.x, v.y, v.z)
    }
    /// An object rotation `deg` (scene-file convention) composed with the tilt.
    fn r(&self, deg: [f32; 3]) -> String {
        let d = Vec3::from(deg) * (std::f32::consts::PI / 180.0);
        let q = self.tilt() * Quat::from_euler(EulerRot::ZYX, d.z, d.y, d.x);
        let (z, y, x) = q.to_euler(EulerRot::ZYX);
        format!("[{:.9e}, {:.9e}, {:.9e}]", x.to_degrees(), y.to_degrees(), z.to_degrees())
    }
    /// A direction: tilted, not scaled or moved.
    fn dir(&self, v: [f32; 3]) -> String {
        let v = self.tilt() * Vec3::from(v);
        format!("[{:.9e}, {:.9e}, {:.9e}]", v.x, v.y, v.z)
    }
    fn s(&self, v: f32) -> String {
        format!("{:.9e}", v * self.scale)
    }
}

/// Ground plane, a point light at (0, 4, 0) and a 1 x 1 horizontal square
/// at height 2 with material `occluder`: the shadow is the square
/// [-1, 1] x [-1, 1] on the ground.
pub fn shadow_scene(f: Frame, occluder: &str) -> String {
    format!(
        r#"
[environment]
color = [0.0, 0.0, 0.0]

[[camera]]
position = {cam}
target = {target}
up = {up}
yfov_deg = 60
znear = {znear}

[[light]]
type = "point"
position = {light}
intensity = {intensity:.9e}

[[material]]
name = "ground"
base_color = [0.8, 0.8, 0.8]
metallic = 0.0
roughness = 1.0
ior = 1.0

{occluder}

[[object]]
name = "ground"
primitive = "plane"
size = [{g}, {g}]
translation = {origin}
rotation_deg = {flat}
material = "ground"

[[object]]
name = "occluder"
primitive = "plane"
size = [{one}, {one}]
translation = {occ}
rotation_deg = {flat}
material = "occluder"
"#,
        cam = f.p([2.5, 7.0, 2.5]),
        target = f.p([0.0, 0.0, 0.0]),
        up = f.dir([0.0, 1.0, 0.0]),
        znear = f.s(0.05),
        light = f.p([0.0, 4.0, 0.0]),
        intensity = 50.0 * f.scale * f.scale,
        g = f.s(40.0),
        origin = f.p([0.0, 0.0, 0.0]),
        one = f.s(1.0),
        occ = f.p([0.0, 2.0, 0.0]),
        flat = f.r([0.0, 0.0, 0.0]),
    )
}

pub const OPAQUE_OCCLUDER: &str = r#"
[[material]]
name = "occluder"
base_color = [0.1, 0.1, 0.1]
roughness = 1.0
double_sided = true
"#;

/// A glass square (transmission 1) tinted `tint`, as the shadow scene's occluder.
pub fn glass_occluder(tint: [f32; 3]) -> String {
    format!(
        r#"
[[material]]
name = "occluder"
base_color = [{}, {}, {}]
transmission = 1.0
ior = 1.5
roughness = 0.0
double_sided = true
"#,
        tint[0], tint[1], tint[2]
    )
}

/// A metal mirror at z = 0 facing +z, an emissive wall at z = 6 facing it,
/// the camera in between looking at the mirror.
pub fn mirror_scene(f0: [f32; 3], wall: [f32; 3]) -> String {
    format!(
        r#"
[environment]
color = [0.0, 0.0, 0.0]

[[camera]]
position = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
yfov_deg = 40

[[light]]
type = "directional"
direction = [0.0, -1.0, 0.0]
intensity = 0.0

[[material]]
name = "mirror"
base_color = [{}, {}, {}]
metallic = 1.0
roughness = 0.0

[[material]]
name = "wall"
base_color = [0.0, 0.0, 0.0]
emissive = [{}, {}, {}]
roughness = 1.0

[[object]]
name = "mirror"
primitive = "plane"
size = [4.0, 4.0]
rotation_deg = [90.0, 0.0, 0.0]
material = "mirror"

[[object]]
name = "wall"
primitive = "plane"
size = [40.0, 40.0]
translation = [0.0, 0.0, 6.0]
rotation_deg = [-90.0, 0.0, 0.0]
material = "wall"
"#,
        f0[0], f0[1], f0[2], wall[0], wall[1], wall[2]
    )
}

/// Two mirrors facing each other with a ball between them.
pub const FACING_MIRRORS: &str = r#"
[environment]
color = [0.3, 0.3, 0.3]

[[camera]]
position = [0.3, 0.2, 1.5]
target = [0.0, 0.0, -2.0]
yfov_deg = 60

[[light]]
type = "point"
position = [0.0, 1.5, 0.0]
intensity = 10.0

[[material]]
name = "mirror"
base_color = [0.98, 0.98, 0.98]
metallic = 1.0
roughness = 0.0

[[material]]
name = "orange"
base_color = [1.0, 0.4, 0.0]

[[object]]
name = "front"
primitive = "plane"
size = [10.0, 10.0]
translation = [0.0, 0.0, -2.0]
rotation_deg = [90.0, 0.0, 0.0]
material = "mirror"

[[object]]
name = "back"
primitive = "plane"
size = [10.0, 10.0]
translation = [0.0, 0.0, 2.0]
rotation_deg = [-90.0, 0.0, 0.0]
material = "mirror"

[[object]]
name = "ball"
primitive = "sphere"
radius = 0.3
translation = [0.0, -0.3, 0.0]
material = "orange"
"#;

/// Mirror ball, glass ball, box, ground; point, spot and directional lights.
pub const AGREEMENT: &str = r#"
[environment]
color = [0.3, 0.4, 0.6]

[[camera]]
position = [0.0, 2.5, 6.0]
target = [0.0, 0.5, 0.0]
yfov_deg = 50

[[light]]
type = "point"
position = [2.0, 5.0, 2.0]
intensity = 60.0

[[light]]
type = "spot"
position = [-3.0, 4.0, 1.0]
direction = [0.6, -0.8, -0.2]
intensity = 80.0
outer_cone_deg = 35
inner_cone_deg = 20

[[light]]
type = "directional"
direction = [-0.3, -1.0, -0.5]
intensity = 2.0

[[material]]
name = "mirror"
base_color = [0.9, 0.9, 0.9]
metallic = 1.0
roughness = 0.0

[[material]]
name = "glass"
base_color = [1.0, 1.0, 1.0]
transmission = 1.0
ior = 1.5
roughness = 0.0

[[material]]
name = "red"
base_color = [0.8, 0.1, 0.1]
roughness = 0.7

[[material]]
name = "ground"
base_color = [0.7, 0.7, 0.7]
roughness = 0.8

[[object]]
name = "ground"
primitive = "plane"
size = [20.0, 20.0]
material = "ground"

[[object]]
name = "mirror ball"
primitive = "sphere"
radius = 0.8
translation = [-1.2, 0.8, 0.0]
material = "mirror"

[[object]]
name = "glass ball"
primitive = "sphere"
radius = 0.8
translation = [1.2, 0.8, 0.5]
material = "glass"

[[object]]
name = "box"
primitive = "cube"
size = 1.0
translation = [0.3, 0.5, -2.0]
rotation_deg = [0.0, 30.0, 0.0]
material = "red"
"#;

/// A white 4x4 floor (4 vertices; tests/render/prt.rs subdivides it) under a
/// sphere of radius 1 centred at height 2; the camera looks at the origin
/// from the side, under the sphere. No light: the frame is the ambient
/// term. Under a constant environment L the unoccluded ambient irradiance
/// of a floor point at distance D from the centre is pi L (1 - r^2 d / D^3)
/// (pi L (1 - (r/d)^2) below the centre); the sphere's underside sees the
/// floor (tests/render/prt.rs, tests/report/prt_report.rs).
pub const PLANE_UNDER_SPHERE: &str = r#"
[[camera]]
position = [3.0, 0.6, 0.0]
target = [0.0, 0.0, 0.0]
yfov_deg = 60

[[light]]
type = "directional"
direction = [0.0, -1.0, 0.0]
intensity = 0.0

[[material]]
name = "white"
base_color = [0.8, 0.8, 0.8]
roughness = 1.0

[[object]]
name = "floor"
primitive = "plane"
size = [4.0, 4.0]
material = "white"

[[object]]
name = "ball"
primitive = "sphere"
radius = 1.0
slices = 32
stacks = 16
translation = [0.0, 2.0, 0.0]
material = "white"
"#;

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
    let mut png = Vec::new();
    texture.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
    let mut bin: Vec<u8> = Vec::new();
    let (s, r) = (half, uv_repeat);
    let mut put = |v: &[f32]| bin.extend(v.iter().flat_map(|x| x.to_le_bytes()));
    for p in [[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0]] {
        put(&p);
    }
    for _ in 0..4 {
        put(&[0.0, 0.0, 1.0]);
    }
    for uv in [[0.0, r], [r, r], [r, 0.0], [0.0, 0.0]] {
        put(&uv);
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "name": "fence"}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}, "indices": 3, "material": 0}}]}}],
  "materials": [{{"name": "stripes", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": true,
    "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicFactor": 0.0, "roughnessFactor": 1.0}}}}],
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
