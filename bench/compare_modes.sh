#!/usr/bin/env bash
# Hybrid against pure ray tracing on every shipped scene: `bench
# --compare-modes`, the two modes interleaved frame by frame, one markdown row
# per scene with pure RT's frame time over hybrid's (>= 1: hybrid is as fast
# or faster): the ratio of the medians and the paired per-frame ratio
# (median [quartiles]), and what auto primary visibility chose.
# Usage: bash bench/compare_modes.sh [width height frames warmup backend]
# (defaults 160 90 40 10 compute); BIN overrides the binary.
set -euo pipefail
cd "$(dirname "$0")/.."
w=${1:-160} h=${2:-90} frames=${3:-40} warmup=${4:-10} backend=${5:-compute}
if [ -z "${BIN:-}" ]; then
  cargo build --locked -q
  BIN=${CARGO_TARGET_DIR:-target}/debug/hybrid-rt
fi
echo "# hybrid / pure RT, $(date -u '+%Y-%m-%d %H:%M UTC'), ${w}x${h}, $frames frames after $warmup warm-up, backend $backend, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| scene | hybrid ms | pure RT ms | RT / hybrid, medians | RT / hybrid, paired [quartiles] | auto visibility (hybrid) |"
echo "|---|---|---|---|---|---|"
for toml in assets/*.toml; do
  scene=$(basename "$toml" .toml)
  log=$(mktemp)
  "$BIN" --log warn bench --scene "$toml" --width "$w" --height "$h" --frames "$frames" --warmup "$warmup" \
    --backend "$backend" --compare-modes > "$log" 2> "$log.err" || { cat "$log.err" >&2; exit 1; }
  side=$(sed -n '/^side by side/,$p' "$log")
  hyb=$(echo "$side" | sed -n 2p)
  rt=$(echo "$side" | sed -n 3p)
  vis=$(grep -m1 '^primary visibility' "$log" | sed 's/^primary visibility: auto, //' || true)
  ms() { echo "$1" | awk '{print $1}'; }
  ratio=$(echo "$rt" | awk '{print $3}')
  paired=$(echo "$rt" | grep -o 'paired [0-9.]* \[[0-9., ]*\]' | sed 's/^paired //')
  echo "| $scene | $(ms "$hyb") | $(ms "$rt") | ${ratio%x} | $paired | ${vis:--} |"
  rm -f "$log" "$log.err"
done
