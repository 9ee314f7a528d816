//! A RenderDoc capture of one frame, opened and checked by RenderDoc itself.
//!
//! `renderdoccmd capture` (RenderDoc 1.24, Debian 12's package, installed by
//! .ci/setup-debian.sh) runs `hybrid-rt render --capture-frame 0` with
//! validation on lavapipe. Under RenderDoc 1.24 lavapipe is a Vulkan 1.2
//! device without ray tracing, so this is also the end-to-end check of the
//! 1.2 extension path and of `--backend auto` falling back to the compute
//! tracer. tests/renderdoc_check.py then replays the capture with RenderDoc's
//! Python module (on lavapipe) and lists its debug-label regions and named
//! resources: every pass of the frame must be there by its label, its targets
//! and the compute BVH's buffers by their names. The passes and targets are
//! listed here ([`PASSES`], [`TARGETS`]), not read from the program's log: the
//! log only has to agree with the lists, so a pass that loses its label, or a
//! frame that loses a pass, fails.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Debian's interpreter: python3-renderdoc installs its module for it
/// (a python3 earlier in PATH, e.g. pyenv's, would not find it).
const PYTHON: &str = "/usr/bin/python3";

/// The passes of the default scene's frame here (hybrid mode, raster
/// visibility, compute tracer, fixed exposure, edge AA; src/render/passes
/// FRAME in order, less those the log says it leaves out: visibility trace,
/// primary, heuristic, shadow_map, reference, terms, inject, luminance,
/// fxaa), each a debug-label region of the capture.
const PASSES: &[&str] = &[
    "gbuffer",
    "gbuffer resolve",
    "direct",
    "ao",
    "ao filter",
    "specular",
    "glossy",
    "glossy filter",
    "composite",
    "tonemap",
    "edge aa",
];

/// Recorded after the frame's passes, in the same command buffer.
const READBACK: &str = "readback";

/// The frame's render targets (each pass module's `TargetDesc`), each a
/// named image in the capture.
const TARGETS: &[&str] = &[
    "gbuffer hit (instance, primitive)",
    "gbuffer depth (reversed-Z)",
    "gbuffer albedo+occlusion",
    "gbuffer normal (octahedral)",
    "gbuffer metallic+roughness+transmission",
    "direct light",
    "ambient visibility sample",
    "ambient bounce sample",
    "ambient visibility",
    "specular chain",
    "work list",
    "glossy sample",
    "reflected radiance",
    "hdr radiance",
    "tonemapped output",
    "anti-aliased output",
];

/// The compute BVH's buffers (accel/compute_bvh.rs names them).
const BVH_BUFFERS: &[&str] =
    &["BVH BLAS nodes", "BVH BLAS triangle order", "BVH top-level nodes", "BVH instances"];

/// Runs `cmd` to completion with its output collected, killing it after `limit`.
fn run(mut cmd: Command, limit: Duration) -> Output {
    let what = format!("{cmd:?}");
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap_or_else(|e| {
        panic!("{what}: {e} (install renderdoccmd and python3-renderdoc: .ci/setup-debian.sh)")
    });
    // Readers on threads, so a full pipe cannot stall the child.
    let mut pipes = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let out = std::thread::spawn(move || {
        let mut b = Vec::new();
        pipes.0.read_to_end(&mut b).unwrap();
        b
    });
    let err = std::thread::spawn(move || {
        let mut b = Vec::new();
        pipes.1.read_to_end(&mut b).unwrap();
        b
    });
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("{what}: still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    Output { status, stdout: out.join().unwrap(), stderr: err.join().unwrap() }
}

/// The text after `key` on the first log line that has it.
fn logged<'a>(log: &'a str, key: &str) -> &'a str {
    log.lines()
        .find_map(|l| l.split_once(key).map(|(_, rest)| rest.trim()))
        .unwrap_or_else(|| panic!("the log has no '{key}' line:\n{log}"))
}

/// Captures frame 0 of the default scene under renderdoccmd; returns the log
/// and the capture file.
fn capture(dir: &Path) -> (String, PathBuf) {
    let mut cmd = Command::new("renderdoccmd");
    cmd.args(["capture", "--wait-for-exit", "--capture-file"])
        .arg(dir.join("hybrid-rt"))
        .arg(env!("CARGO_BIN_EXE_hybrid-rt"))
        .args([
            "--validation",
            "--log",
            "info",
            "render",
            "--width",
            "96",
            "--height",
            "54",
            "--capture-frame",
            "0",
        ])
        .arg("--scene")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.toml"))
        .arg("--out")
        .arg(dir.join("frame.png"))
        .env_remove("RUST_LOG");
    let out = run(cmd, Duration::from_secs(300));
    let log = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    // renderdoccmd exits 0 whatever its child does: the child's own error
    // line and the written frame tell.
    assert!(out.status.success() && !log.contains("error:"), "capture run failed:\n{log}");
    assert!(!log.contains(" ERROR "), "validation (or other) errors under RenderDoc:\n{log}");
    assert!(dir.join("frame.png").exists(), "no frame written:\n{log}");
    let path = PathBuf::from(logged(&log, "renderdoc: captured render frame 0 to "));
    assert!(path.exists(), "logged capture {} does not exist:\n{log}", path.display());
    (log, path)
}

#[test]
fn a_captured_frame_shows_every_pass_and_named_object() {
    let started = Instant::now();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("renderdoc");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (log, rdc) = capture(&dir);

    // What RenderDoc 1.24 makes of lavapipe: 1.2, no ray tracing.
    let device = logged(&log, "INFO  hybrid_rt::vk] using ");
    assert!(
        device.contains(
            "Vulkan 1.2 + extensions VK_KHR_synchronization2, VK_KHR_dynamic_rendering, VK_EXT_extended_dynamic_state"
        ),
        "{device}"
    );
    assert!(
        device.contains("ray-tracing extensions enabled: AS false / query false / pipeline false"),
        "{device}"
    );
    let frame = logged(&log, "frame: mode ");
    assert!(
        frame.contains("backend compute") && frame.contains("(auto: no ray-tracing extension"),
        "{frame}"
    );

    // The frame the log describes is the one listed above: a pass or target
    // added to (or dropped from) this frame is added to the lists, so none
    // goes unchecked below.
    let logged_passes: Vec<&str> = logged(&log, "frame: passes ").split(" -> ").collect();
    assert_eq!(logged_passes, PASSES, "the frame's passes changed: update PASSES");
    let mut logged_targets: Vec<&str> = logged(&log, "frame: targets ")
        .split(" = ")
        .next()
        .unwrap()
        // "name (8 B), name (4 B)": names may hold ", " themselves.
        .split(" B), ")
        .map(|t| t.rsplit_once(" (").map_or(t, |(name, _)| name))
        .collect();
    let mut targets = TARGETS.to_vec();
    logged_targets.sort();
    targets.sort();
    assert_eq!(logged_targets, targets, "the frame's targets changed: update TARGETS");

    let mut py = Command::new(PYTHON);
    py.arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/renderdoc_check.py")).arg(&rdc);
    let out = run(py, Duration::from_secs(120));
    let listing = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "replay failed:\n{listing}{}", String::from_utf8_lossy(&out.stderr));
    let mut markers = Vec::new();
    let mut resources = Vec::new();
    for line in listing.lines() {
        match line.split('\t').collect::<Vec<_>>().as_slice() {
            ["marker", _depth, name] => markers.push(name.to_string()),
            ["resource", name] => resources.push(name.to_string()),
            ["version", v, driver] => eprintln!("replayed with RenderDoc {v} ({driver})"),
            _ => panic!("unexpected line from renderdoc_check.py: {line}"),
        }
    }
    eprintln!("markers: {markers:?}");
    let passes: Vec<&str> = PASSES.iter().copied().chain([READBACK]).collect();
    let missing_passes: Vec<_> = passes.iter().filter(|p| !markers.iter().any(|m| m == *p)).collect();
    assert!(
        missing_passes.is_empty(),
        "passes without their label in the capture: {missing_passes:?}\n{listing}"
    );
    // Each pass once: the capture holds exactly the one frame.
    for p in &passes {
        assert_eq!(markers.iter().filter(|m| m == p).count(), 1, "pass {p} in {markers:?}");
    }
    let missing_names: Vec<_> =
        TARGETS.iter().chain(BVH_BUFFERS).copied().filter(|n| !resources.iter().any(|r| r == n)).collect();
    assert!(missing_names.is_empty(), "objects that lost their names: {missing_names:?}\n{listing}");
    eprintln!("capture + replay + checks: {:.1} s", started.elapsed().as_secs_f64());
}
