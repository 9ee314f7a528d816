#!/usr/bin/env bash
# Runs the standard benchmarks and writes their tables to bench/results/.
# Usage: bash bench/run.sh [label] [all|frame|animation]
#   label     defaults to the host name; results go to bench/results/<label>.md
#             (frame tables) and bench/results/<label>-animation.md
#   sections  default all
# Everything is measured side by side within one process per table: same
# device, scene, resolution and camera path.
set -euo pipefail
cd "$(dirname "$0")/.."
label=${1:-$(hostname)}
what=${2:-all}
out=bench/results
mkdir -p "$out"
cargo build --locked
bin=${CARGO_TARGET_DIR:-target}/debug/hybrid-rt
header() { echo "# $label, $(date -u +%Y-%m-%d), $($bin info | head -3 | tr '\n' ' ')"; echo; }

frame_tables() {
  header
  echo "## Hybrid vs pure ray tracing, Sponza with spheres, 320x180"
  $bin --log warn bench --scene assets/sponza_spheres.toml --width 320 --height 180 \
    --frames 10 --warmup 2 --compare-modes
  echo "## Ray backends side by side, Sponza with spheres, 320x180 (hybrid)"
  $bin --log warn bench --scene assets/sponza_spheres.toml --width 320 --height 180 \
    --frames 5 --warmup 1 --compare-backends
  echo "## Ray backends side by side, default scene, 320x180 (hybrid)"
  $bin --log warn bench --width 320 --height 180 --frames 10 --warmup 2 --compare-backends
  echo "## Every backend in both modes, armadillo in glass, 320x180 (per-pass GPU ms by stage)"
  $bin --log warn bench --scene assets/armadillo_glass.toml --width 320 --height 180 \
    --frames 3 --warmup 1 --compare-backends --compare-modes
}

animation_tables() {
  header
  fox=../shared/assets/gltf/Fox/glTF/Fox.gltf
  echo "## Skinned model (Fox, 'Run', 576 triangles), 320x180: skinning + refit vs rebuild vs full rebuild"
  $bin --log warn bench --scene "$fox" --animation Run --width 320 --height 180 \
    --frames 20 --warmup 2 --compare-backends --compare-accel-updates
  echo "## Rebuild policy (refit; rebuild past 1.5x bounds area), Fox 'Run', 60 frames"
  $bin --log warn bench --scene "$fox" --animation Run --width 160 --height 90 \
    --frames 60 --warmup 0 --compare-backends --accel-update policy
  echo "## 1,000 orbiting spheres (rigid instances, 144 triangles each), 320x180"
  spheres=$(mktemp --suffix .toml)
  bash bench/orbit_spheres.sh 1000 "$spheres" >/dev/null
  $bin --log warn bench --scene "$spheres" --animation scene --width 320 --height 180 \
    --frames 5 --warmup 1 --compare-backends --compare-accel-updates
  rm -f "$spheres"
  echo "## Animated Sponza (spheres orbiting the courtyard), 320x180"
  $bin --log warn bench --scene assets/sponza_animated.toml --animation scene --width 320 \
    --height 180 --frames 5 --warmup 1 --compare-backends
}

case $what in
  all | frame) frame_tables | tee "$out/$label.md" ;;&
  all | animation) animation_tables | tee "$out/$label-animation.md" ;;
  all | frame) ;;
  *) echo "unknown section '$what' (all, frame, animation)" >&2; exit 2 ;;
esac
