//! Values shared by Rust and GLSL have one source (src/gpu/shared_values.rs):
//! the generated header the shaders were compiled with must say exactly what
//! the Rust constants say, no shader may spell a set, binding or
//! specialization-constant number as a literal, and the strides of the
//! host/shader structs in the compiled SPIR-V must equal the Rust sizes.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use hybrid_rt::gpu::shared;
use hybrid_rt::vk::pipeline::spirv;

#[test]
fn generated_header_matches_the_rust_constants() {
    let mut defined = HashMap::new();
    for line in shared::GLSL_HEADER.lines() {
        let Some(rest) = line.strip_prefix("#define ") else { continue };
        let mut parts = rest.split_whitespace();
        let (Some(name), Some(value)) = (parts.next(), parts.next()) else { continue };
        if name == "SHARED_GLSL" {
            continue;
        }
        let v: f64 = value.trim_end_matches('u').parse().unwrap_or_else(|_| panic!("{name} = {value}"));
        defined.insert(name.to_string(), v);
    }
    assert_eq!(defined.len(), shared::ALL.len(), "header and constant table differ in size");
    for (name, value) in shared::ALL {
        let v = defined.get(*name).unwrap_or_else(|| panic!("{name} missing from generated/shared.glsl"));
        assert_eq!(*v as f32, *value as f32, "{name}: GLSL {v}, Rust {value}");
    }
}

fn glsl_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            glsl_files(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// `set = 2`, `binding = 0`, `constant_id = 3` written as numbers would
/// drift from the Rust side the day one side changes.
#[test]
fn shaders_name_their_sets_bindings_and_constant_ids() {
    let mut files = Vec::new();
    glsl_files(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("glsl"), &mut files);
    let mut offenders = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for key in ["set", "binding", "constant_id"] {
                let mut rest = code;
                while let Some(i) = rest.find(key) {
                    let after = rest[i + key.len()..].trim_start();
                    let word_start = i == 0
                        || !rest.as_bytes()[i - 1].is_ascii_alphanumeric() && rest.as_bytes()[i - 1] != b'_';
                    if word_start {
                        if let Some(v) = after.strip_prefix('=') {
                            if v.trim_start().starts_with(|c: char| c.is_ascii_digit()) {
                                offenders.push(format!("{}:{}: {}", f.display(), n + 1, line.trim()));
                            }
                        }
                    }
                    rest = &rest[i + key.len()..];
                }
            }
            // A shared name defined again in a shader would shadow the source.
            if let Some(rest) = code.trim_start().strip_prefix("#define ") {
                let name = rest.split_whitespace().next().unwrap_or("");
                if shared::ALL.iter().any(|(n, _)| *n == name) {
                    offenders.push(format!("{}:{}: redefines {name}", f.display(), n + 1));
                }
            }
        }
    }
    assert!(offenders.is_empty(), "literal layout numbers in GLSL:\n{}", offenders.join("\n"));
}

/// ArrayStride of the runtime array inside each named buffer block, read
/// from a compiled shader (debug info keeps the block names).
fn block_strides(shader: &str) -> HashMap<String, u32> {
    let words = spirv(shader).unwrap();
    let mut names: HashMap<u32, String> = HashMap::new();
    let mut struct_members: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut strides: HashMap<u32, u32> = HashMap::new();
    let mut runtime_arrays = Vec::new();
    let mut i = 5;
    while i < words.len() {
        let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        let w = &words[i + 1..i + count.max(1)];
        match op {
            5 => {
                // OpName: target, literal string
                let bytes: Vec<u8> = w[1..].iter().flat_map(|x| x.to_le_bytes()).collect();
                let s = bytes.split(|b| *b == 0).next().unwrap_or(&[]);
                names.insert(w[0], String::from_utf8_lossy(s).into_owned());
            }
            71 if w[1] == 6 => {
                strides.insert(w[0], w[2]); // OpDecorate ArrayStride
            }
            29 => runtime_arrays.push(w[0]), // OpTypeRuntimeArray
            30 => {
                struct_members.insert(w[0], w[1..].to_vec()); // OpTypeStruct
            }
            _ => {}
        }
        i += count.max(1);
    }
    let mut out = HashMap::new();
    for (id, members) in &struct_members {
        let (Some(name), Some(last)) = (names.get(id), members.last()) else { continue };
        if runtime_arrays.contains(last) {
            if let Some(s) = strides.get(last) {
                out.insert(name.clone(), *s);
            }
        }
    }
    out
}

#[test]
fn compiled_struct_strides_equal_the_rust_sizes() {
    use hybrid_rt::accel::bvh::BvhNode;
    use hybrid_rt::accel::compute_bvh::GpuBvhInstance;
    use hybrid_rt::gpu::types::{GpuInstance, GpuLight, GpuMaterial};
    let expected = [
        ("Vertices", shared::VERTEX_STRIDE, std::mem::size_of::<hybrid_rt::scene::Vertex>()),
        ("Materials", shared::MATERIAL_STRIDE, std::mem::size_of::<GpuMaterial>()),
        ("Instances", shared::INSTANCE_STRIDE, std::mem::size_of::<GpuInstance>()),
        ("Lights", shared::LIGHT_STRIDE, std::mem::size_of::<GpuLight>()),
        ("BlasNodes", shared::BVH_NODE_STRIDE, std::mem::size_of::<BvhNode>()),
        ("BvhInstances", shared::BVH_INSTANCE_STRIDE, std::mem::size_of::<GpuBvhInstance>()),
    ];
    let mut seen = HashMap::new();
    for shader in ["direct_compute", "specular_compute", "primary_compute", "gbuffer.vert", "specular_query"]
    {
        for (block, stride) in block_strides(shader) {
            seen.entry(block.clone()).or_insert_with(Vec::new).push((shader, stride));
        }
    }
    for (block, shared_stride, rust_size) in expected {
        assert_eq!(shared_stride as usize, rust_size, "{block}: shared stride vs Rust size");
        let found =
            seen.get(block).unwrap_or_else(|| panic!("no compiled shader has block {block}: {seen:?}"));
        for (shader, stride) in found {
            assert_eq!(
                *stride as usize, rust_size,
                "{block} in {shader}: SPIR-V stride {stride}, Rust {rust_size}"
            );
        }
    }
}
