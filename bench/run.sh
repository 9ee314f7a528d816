#!/usr/bin/env bash
# Runs the standard benchmarks and writes their tables to bench/results/.
# Usage: bash bench/run.sh [label]    (label defaults to the host name)
# Everything is measured side by side within one process per table: same
# device, scene, resolution and camera path.
set -euo pipefail
cd "$(dirname "$0")/.."
label=${1:-$(hostname)}
out=bench/results
mkdir -p "$out"
cargo build --locked
bin=./target/debug/hybrid-rt
{
  echo "# $label, $(date -u +%Y-%m-%d), $($bin info | head -3 | tr '\n' ' ')"
  echo
  echo "## Hybrid vs pure ray tracing, Sponza with spheres, 320x180"
  $bin --log warn bench --scene assets/sponza_spheres.toml --width 320 --height 180 \
    --frames 10 --warmup 2 --compare-modes
  echo "## Ray backends side by side, Sponza with spheres, 320x180 (hybrid)"
  $bin --log warn bench --scene assets/sponza_spheres.toml --width 320 --height 180 \
    --frames 5 --warmup 1 --compare-backends
  echo "## Ray backends side by side, default scene, 320x180 (hybrid)"
  $bin --log warn bench --width 320 --height 180 --frames 10 --warmup 2 --compare-backends
  fox=../shared/assets/gltf/Fox/glTF/Fox.gltf
  echo "## Skinned model (Fox, 'Run'), 320x180: skinning + refit vs rebuild vs full rebuild, every backend"
  $bin --log warn bench --scene "$fox" --animation Run --width 320 --height 180 \
    --frames 20 --warmup 2 --compare-backends --compare-accel-updates
  echo "## Rebuild policy (refit; rebuild when the bounds' area grew past 1.5x), Fox 'Run', 60 frames"
  $bin --log warn bench --scene "$fox" --animation Run --width 160 --height 90 \
    --frames 60 --warmup 0 --compare-backends --accel-update policy
} | tee "$out/$label.md"
