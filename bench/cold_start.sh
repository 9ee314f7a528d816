#!/usr/bin/env bash
# First-frame time per backend with an empty and with a warm Mesa shader
# cache: wall-clock time of one `render` (process start to exit) and the
# GPU ms it reports for its only frame. Usage: bench/cold_start.sh [SCENE] [WxH]
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-assets/default.toml}
size=${2:-320x180}
bin=${HYBRID_RT:-target/debug/hybrid-rt}
out=$(mktemp -d)
echo "scene $scene, ${size}, $(date -u +%F), $($bin info 2>/dev/null | grep -m1 -o 'llvmpipe[^)]*)' || echo device)"
printf '%-9s %-6s %8s  %s\n' backend cache wall_s "GPU ms (first frame)"
for backend in query pipeline compute; do
  cache=$(mktemp -d)
  for state in empty warm; do
    start=$(date +%s.%N)
    log=$(MESA_SHADER_CACHE_DIR=$cache "$bin" render --scene "$scene" --width "${size%x*}" --height "${size#*x}" \
      --backend "$backend" --out "$out/$backend.png" 2>&1)
    end=$(date +%s.%N)
    gpu=$(echo "$log" | grep -o 'GPU: .*' | head -1 | sed 's/^GPU: //')
    total=$(echo "$gpu" | grep -o '[0-9.]* ms' | awk '{s+=$1} END {printf "%.0f", s}')
    printf '%-9s %-6s %8.1f  %s ms in all (%s)\n' "$backend" "$state" "$(echo "$end - $start" | bc)" "$total" "$gpu"
  done
  rm -rf "$cache"
done
rm -rf "$out"
