//! Compiles every GLSL shader under `glsl/` to SPIR-V with shaderc.
//!
//! - Each file with a stage extension (vert, frag, comp, rgen, rchit, rahit,
//!   rmiss, rint) is compiled once under its own name.
//! - `glsl/variants.txt` adds preprocessor variants: `out_name: source DEFINE[=VALUE] ...`.
//! - `#include "x.glsl"` resolves relative to the including file, then `glsl/`.
//! - A GLSL error fails the build with shaderc's `file:line: message`.
//!
//! The result is `$OUT_DIR/shaders.rs`: a table of (name, SPIR-V bytes).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const STAGES: &[(&str, shaderc::ShaderKind)] = &[
    ("vert", shaderc::ShaderKind::Vertex),
    ("frag", shaderc::ShaderKind::Fragment),
    ("comp", shaderc::ShaderKind::Compute),
    ("rgen", shaderc::ShaderKind::RayGeneration),
    ("rchit", shaderc::ShaderKind::ClosestHit),
    ("rahit", shaderc::ShaderKind::AnyHit),
    ("rmiss", shaderc::ShaderKind::Miss),
    ("rint", shaderc::ShaderKind::Intersection),
];

struct Job {
    name: String,
    source: PathBuf,
    defines: Vec<(String, Option<String>)>,
}

fn stage_of(path: &Path) -> Option<shaderc::ShaderKind> {
    let ext = path.extension()?.to_str()?;
    STAGES.iter().find(|(e, _)| *e == ext).map(|(_, k)| *k)
}

fn collect_sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> =
        std::fs::read_dir(dir).expect("read glsl/").map(|e| e.expect("dir entry").path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            collect_sources(&p, out);
        } else {
            out.push(p);
        }
    }
}

fn parse_variants(glsl: &Path) -> Vec<Job> {
    let path = glsl.join("variants.txt");
    let Ok(text) = std::fs::read_to_string(&path) else { return Vec::new() };
    let mut jobs = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let (name, rest) = line
            .split_once(':')
            .unwrap_or_else(|| panic!("{}:{}: expected 'name: source DEFINES'", path.display(), n + 1));
        let mut words = rest.split_whitespace();
        let source = glsl.join(
            words.next().unwrap_or_else(|| panic!("{}:{}: missing source file", path.display(), n + 1)),
        );
        let defines = words
            .map(|w| match w.split_once('=') {
                Some((k, v)) => (k.to_string(), Some(v.to_string())),
                None => (w.to_string(), None),
            })
            .collect();
        jobs.push(Job { name: name.trim().to_string(), source, defines });
    }
    jobs
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let glsl = root.join("glsl");
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    println!("cargo:rerun-if-changed=glsl");

    let mut sources = Vec::new();
    collect_sources(&glsl, &mut sources);
    for s in &sources {
        println!("cargo:rerun-if-changed={}", s.display());
    }
    let mut jobs: Vec<Job> = sources
        .iter()
        .filter(|p| stage_of(p).is_some())
        .map(|p| Job {
            name: p.strip_prefix(&glsl).unwrap().to_string_lossy().replace('\\', "/"),
            source: p.clone(),
            defines: Vec::new(),
        })
        .collect();
    jobs.extend(parse_variants(&glsl));

    let compiler = shaderc::Compiler::new().expect("shaderc compiler");
    let mut table = String::from("pub static SHADERS: &[(&str, &[u8])] = &[\n");
    let mut errors = Vec::new();
    for job in &jobs {
        match compile(&compiler, &glsl, job) {
            Ok(spv) => {
                let file = out_dir.join(format!("{}.spv", job.name.replace('/', "__")));
                std::fs::write(&file, spv).expect("write spv");
                writeln!(table, "    ({:?}, include_bytes!({:?})),", job.name, file).unwrap();
            }
            Err(e) => errors.push(format!("shader '{}':\n{}", job.name, e)),
        }
    }
    if !errors.is_empty() {
        panic!("GLSL compilation failed:\n{}", errors.join("\n"));
    }
    table.push_str("];\n");
    std::fs::write(out_dir.join("shaders.rs"), table).expect("write shaders.rs");
}

fn compile(compiler: &shaderc::Compiler, glsl: &Path, job: &Job) -> Result<Vec<u8>, String> {
    let kind = stage_of(&job.source).ok_or_else(|| format!("{}: unknown stage", job.source.display()))?;
    let text = std::fs::read_to_string(&job.source).map_err(|e| format!("{}: {e}", job.source.display()))?;
    let mut opts = shaderc::CompileOptions::new().map_err(|e| format!("shaderc options: {e}"))?;
    opts.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_3 as u32);
    opts.set_target_spirv(shaderc::SpirvVersion::V1_6);
    opts.set_generate_debug_info(); // readable names in RenderDoc / Nsight
    opts.set_optimization_level(shaderc::OptimizationLevel::Performance);
    for (k, v) in &job.defines {
        opts.add_macro_definition(k, v.as_deref());
    }
    let glsl_root = glsl.to_path_buf();
    opts.set_include_callback(move |requested, _ty, requesting, _depth| {
        let from = Path::new(requesting).parent().map(Path::to_path_buf).unwrap_or_default();
        let candidates = [from.join(requested), glsl_root.join(requested)];
        for c in candidates {
            if let Ok(content) = std::fs::read_to_string(&c) {
                println!("cargo:rerun-if-changed={}", c.display());
                return Ok(shaderc::ResolvedInclude { resolved_name: c.to_string_lossy().into(), content });
            }
        }
        Err(format!("cannot find include '{requested}' (from {requesting})"))
    });
    let name = job.source.to_string_lossy();
    compiler
        .compile_into_spirv(&text, kind, &name, "main", Some(&opts))
        .map(|a| a.as_binary_u8().to_vec())
        .map_err(|e| e.to_string())
}
