#!/usr/bin/env bash
# The benches issue 19 item 9 asks for, on a lent GPU machine (the workplace's
# `device` tool: no Rust toolchain and no package registry there, so the
# binary and the assets travel prepared). Prints everything; tee it to a log.
#
# Usage (in the repository root, on the GPU machine):
#   BIN=dev/bin/hybrid-rt ASSETS=dev/assets bash bench/gpu.sh [W H]
# where BIN is a (stripped) build of this tree and ASSETS holds the shared
# assets the shipped scenes name (scenes/SponzaCapsaicin, stanford/armadillo;
# ../shared/assets where that exists). Preparing them on this machine:
#   cargo build --locked && mkdir -p dev/bin && cp $CARGO_TARGET_DIR/debug/hybrid-rt dev/bin
#   strip dev/bin/hybrid-rt   # the tree that travels is limited to 64 MiB
#   Sponza's textures downscaled to 512x512 (the 1024x1024 originals do not
#   fit); every number from such a run says so.
# The driver there offers the RT pipeline but no ray queries: `bench --rays`
# then compares the compute tracer with the pipeline.
set -uo pipefail
cd "$(dirname "$0")/.."
bin=${BIN:-dev/bin/hybrid-rt}
assets=${ASSETS:-../shared/assets}
w=${1:-1920}
h=${2:-1080}
# The GPU idles at a low clock (an H200 read 345 MHz) and every process
# starts after seconds of loading: 300 warm-up frames per variant and 200
# repetitions per ray set let the clock ramp before the measured ones (with
# 10 warm-up frames the first variant of each process read up to 2x slower).
frames=${FRAMES:-60}
warmup=${WARMUP:-300}
reps=${REPS:-200}
# The shipped scenes with their shared assets at $assets (a path relative to
# assets/ or absolute), written beside the originals so that their own
# relative paths (the environment map) still resolve.
case $assets in /*) rel=$assets ;; *) rel=../$assets ;; esac
for s in sponza_spheres sponza_animated armadillo_glass; do
  sed "s#\.\./\.\./shared/assets#$rel#g" "assets/$s.toml" >"assets/gpu_$s.toml"
done
run() {
  echo "\$ hybrid-rt $*"
  local t0=$SECONDS
  timeout 150 "$bin" --log warn "$@"
  echo "(exit $?, $((SECONDS - t0)) s wall)"
  echo
}
"$bin" info
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv 2>/dev/null
# Hybrid with raster primary visibility (the G-buffer from the rasterizer),
# as a GPU runs it; `auto` would spend probe frames on the camera path.
echo "## ${w}x${h}, Sponza with spheres, all effects: hybrid vs pure RT, RT pipeline and compute tracer"
for b in pipeline compute; do
  run bench --scene assets/gpu_sponza_spheres.toml --width "$w" --height "$h" --backend "$b" \
    --frames "$frames" --warmup "$warmup" --compare-modes --primary-visibility raster
done
echo "## Ray microbenchmark, ${w}x${h} primary rays: compute tracer vs the driver's"
run bench --rays --scene assets/gpu_sponza_spheres.toml --width "$w" --height "$h" --ray-reps "$reps"
run bench --rays --scene assets/gpu_armadillo_glass.toml --width "$w" --height "$h" --ray-reps "$reps"
echo "## ${w}x${h}, the other shipped scenes: hybrid vs pure RT per backend"
for s in assets/default.toml assets/aa_edges.toml assets/gpu_armadillo_glass.toml assets/gpu_sponza_animated.toml; do
  for b in pipeline compute; do
    run bench --scene "$s" --width "$w" --height "$h" --backend "$b" --frames "$frames" --warmup "$warmup" \
      --compare-modes --primary-visibility raster
  done
done
nvidia-smi --query-gpu=clocks.sm,clocks.mem --format=csv 2>/dev/null
rm -f assets/gpu_*.toml
