//! Corrupted inputs (truncated, bit-flipped, huge counts) of small valid
//! seeds: every load ends in an error or a scene, never a panic, a hang or a
//! huge allocation. Fixed-seed PRNG: a failure names its case, reproducibly.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use hybrid_rt::scene::Scene;

mod common;
use common::base64;

/// Refuses any single allocation over 256 MiB (the seeds are a few hundred
/// bytes, so only an unchecked count can ask for that) after saying which
/// case asked; the refusal aborts the test.
struct Capped;
const CAP: usize = 256 << 20;
static CASE: AtomicUsize = AtomicUsize::new(usize::MAX);

unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if layout.size() > CAP {
            // No formatting here: it would allocate.
            let mut digits = [0u8; 20];
            let (mut n, mut i) = (CASE.load(Ordering::Relaxed), 20);
            while i > 0 {
                i -= 1;
                digits[i] = b'0' + (n % 10) as u8;
                n /= 10;
                if n == 0 {
                    break;
                }
            }
            let mut err = std::io::stderr();
            let _ = err.write_all(b"fuzz_loader: allocation over 256 MiB in case ");
            let _ = err.write_all(&digits[i..]);
            let _ = err.write_all(b"\n");
            return std::ptr::null_mut();
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Capped = Capped;

struct XorShift(u64);
impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Triangle positions, u16 indices (+2 padding), key times, translations.
fn bin() -> Vec<u8> {
    let floats = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let mut b: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    b.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()));
    b.extend([0.0f32, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|f| f.to_le_bytes()));
    b
}

/// glTF JSON; `uri` None means the GLB BIN chunk.
fn gltf_json(uri: Option<&str>) -> String {
    let uri = uri.map(|u| format!(r#""uri": "{u}", "#)).unwrap_or_default();
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
"nodes": [{{"mesh": 0, "children": [1]}}, {{"camera": 0}}],
"cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "znear": 0.1}}}}],
"meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
"buffers": [{{{uri}"byteLength": 76}}],
"bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}},
  {{"buffer": 0, "byteOffset": 44, "byteLength": 8}}, {{"buffer": 0, "byteOffset": 52, "byteLength": 24}}],
"accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
  {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}},
  {{"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR"}},
  {{"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}}],
"animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 0, "path": "translation"}}}}],
  "samplers": [{{"input": 2, "output": 3}}]}}]}}"#
    )
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().div_ceil(4) * 4, b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().div_ceil(4) * 4, 0);
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((28 + json.len() + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

const OBJ: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 2 4 3\n";

const TOML: &str = r#"[[light]]
type = "point"
position = [0.0, 2.0, 0.0]
intensity = 5.0
[[material]]
name = "m"
roughness = 0.3
[environment]
hdr = "seed.hdr"
[[object]]
name = "ball"
primitive = "sphere"
slices = 8
stacks = 4
material = "m"
[[object]]
name = "mesh"
obj = "seed.obj"
[[object]]
name = "model"
gltf = "seed.gltf"
translation = [1.0, 0.0, 0.0]
"#;

/// Huge values for the "huge count" mutations.
const HUGE: [&str; 5] = ["2147483648", "4294967295", "1152921504606846976", "18446744073709551615", "-1"];

/// Every run of digits after one of `keys` replaced by each huge value.
fn huge_counts(text: &str, keys: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    for key in keys {
        for (at, _) in text.match_indices(key) {
            let start =
                at + key.len() + text[at + key.len()..].find(|c: char| c.is_ascii_digit()).unwrap_or(0);
            let end = start + text[start..].find(|c: char| !c.is_ascii_digit()).unwrap_or(0);
            for v in HUGE {
                out.push(format!("{}{v}{}", &text[..start], &text[end..]));
            }
        }
    }
    out
}

/// Loads `path` in a worker thread: Ok(()) for an error or a scene, Err for
/// a panic or a load taking over 10 s.
fn load_bounded(path: &Path) -> Result<(), String> {
    let (tx, rx) = std::sync::mpsc::channel();
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        let result = std::panic::catch_unwind(|| drop(Scene::load(&path)));
        let _ = tx.send(result.is_ok());
    });
    match rx.recv_timeout(Duration::from_secs(10)) {
        Ok(true) => Ok(()),
        Ok(false) | Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => Err("panicked".into()),
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => Err("took over 10 s".into()),
    }
}

struct Seed {
    file: &'static str,
    /// The file loaded to read this one (an image is read through the scene
    /// that references it); None: the file itself.
    via: Option<&'static str>,
    bytes: Vec<u8>,
    /// Huge-count variants (whole files).
    huge: Vec<Vec<u8>>,
}

/// A 4x4 RGBA PNG and a 4x2 Radiance .hdr, encoded by the image crate.
fn png() -> Vec<u8> {
    let px: Vec<u8> = (0..64u8).map(|i| i.wrapping_mul(37)).collect();
    let mut out = std::io::Cursor::new(Vec::new());
    image::RgbaImage::from_raw(4, 4, px).unwrap().write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn hdr() -> Vec<u8> {
    let px: Vec<image::Rgb<f32>> = (0..8).map(|i| image::Rgb([i as f32 * 0.5, 1.0, 1e4])).collect();
    let mut out = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut out).encode(&px, 4, 2).unwrap();
    out
}

/// A glTF whose material's base colour is seed.png.
const TEXTURED_GLTF: &str = r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
"nodes": [{"mesh": 0}],
"meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
"materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
"textures": [{"source": 0}], "images": [{"uri": "seed.png"}],
"buffers": [{"uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/", "byteLength": 60}],
"bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
"accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
  {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}]}"#;

fn seeds() -> Vec<Seed> {
    let data = format!("data:application/octet-stream;base64,{}", base64(&bin()));
    let json = gltf_json(Some(&data));
    let glb_json = gltf_json(None);
    let counts = ["\"count\": ", "\"byteLength\": ", "\"byteOffset\": ", "\"yfov\": "];
    vec![
        Seed {
            file: "seed.gltf",
            via: None,
            bytes: json.clone().into(),
            huge: huge_counts(&json, &counts).into_iter().map(Into::into).collect(),
        },
        Seed {
            file: "seed.glb",
            via: None,
            bytes: glb(&glb_json, &bin()),
            huge: huge_counts(&glb_json, &counts).iter().map(|j| glb(j, &bin())).collect(),
        },
        Seed {
            file: "seed.obj",
            via: None,
            bytes: OBJ.into(),
            huge: huge_counts(OBJ, &["f ", "/"]).into_iter().map(Into::into).collect(),
        },
        Seed {
            file: "seed.toml",
            via: None,
            bytes: TOML.into(),
            huge: huge_counts(TOML, &["slices = ", "stacks = "]).into_iter().map(Into::into).collect(),
        },
        Seed { file: "textured.gltf", via: None, bytes: TEXTURED_GLTF.into(), huge: Vec::new() },
        // Image decoders: corrupted texture and environment files, read
        // through the scenes that reference them.
        Seed { file: "seed.png", via: Some("textured.gltf"), bytes: png(), huge: Vec::new() },
        Seed { file: "seed.hdr", via: Some("seed.toml"), bytes: hdr(), huge: huge_hdr() },
    ]
}

/// .hdr headers claiming huge sizes (the decoder must not allocate them).
fn huge_hdr() -> Vec<Vec<u8>> {
    let valid = hdr();
    let header_end = valid.windows(2).position(|w| w == b"\n-").unwrap() + 1;
    let body = &valid[valid[header_end..].iter().position(|b| *b == b'\n').unwrap() + header_end + 1..];
    ["-Y 2 +X 4000000000", "-Y 2000000000 +X 4", "-Y 65536 +X 65536", "-Y 0 +X 4", "-Y 2 +X -4"]
        .iter()
        .map(|size| [&valid[..header_end], size.as_bytes(), b"\n", body].concat())
        .collect()
}

/// Named inputs that once panicked, hung or over-allocated.
fn regressions() -> Vec<(&'static str, &'static str, Vec<u8>)> {
    vec![(
        "sphere with 2^31 slices overflowed the vertex count (panic)",
        "seed.toml",
        TOML.replace("slices = 8", "slices = 2147483648").into(),
    )]
}

#[test]
fn corrupted_inputs_never_panic_hang_or_over_allocate() {
    let dir = std::env::temp_dir().join("hybrid-rt-tests").join("fuzz-loader");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let seeds = seeds();
    // The valid seeds load (the TOML needs the others beside it).
    for seed in &seeds {
        std::fs::write(dir.join(seed.file), &seed.bytes).unwrap();
    }
    for seed in &seeds {
        let load = seed.via.unwrap_or(seed.file);
        Scene::load(&dir.join(load))
            .unwrap_or_else(|e| panic!("seed {} ({load}) does not load: {e:#}", seed.file));
    }
    const SEED: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut rng = XorShift(SEED);
    let mut cases: Vec<(String, &'static str, Vec<u8>)> = Vec::new();
    for (name, file, bytes) in regressions() {
        cases.push((format!("regression: {name}"), file, bytes));
    }
    for seed in &seeds {
        let len = seed.bytes.len();
        for k in 0..60 {
            let cut = k * len / 60;
            cases.push((
                format!("{} truncated to {cut} bytes", seed.file),
                seed.file,
                seed.bytes[..cut].to_vec(),
            ));
        }
        for k in 0..200 {
            let mut bytes = seed.bytes.clone();
            for _ in 0..1 + rng.below(4) {
                let i = rng.below(len);
                bytes[i] ^= 1 << rng.below(8);
            }
            cases.push((format!("{} bit flip #{k}", seed.file), seed.file, bytes));
        }
        for (k, bytes) in seed.huge.iter().enumerate() {
            cases.push((format!("{} huge count #{k}", seed.file), seed.file, bytes.clone()));
        }
    }
    assert!(cases.len() >= 1000, "only {} cases", cases.len());
    let mut failures = Vec::new();
    for (index, (name, file, bytes)) in cases.iter().enumerate() {
        // Each case writes its seed's file; the others stay valid beside it.
        let path: PathBuf = dir.join(file);
        std::fs::write(&path, bytes).unwrap();
        CASE.store(index, Ordering::Relaxed);
        let original = seeds.iter().find(|s| s.file == *file).unwrap();
        if let Err(why) = load_bounded(&dir.join(original.via.unwrap_or(file))) {
            failures.push(format!("case {index} ({name}, PRNG seed {SEED:#x}): {why}"));
        }
        std::fs::write(&path, &original.bytes).unwrap();
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
