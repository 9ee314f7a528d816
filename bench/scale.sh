#!/usr/bin/env bash
# Cost against size (issue 36 item 1, until `bench --scale` exists): generated terrains of 1e4 to
# 4e6 unique triangles (`primitive = "terrain"`), one `render` process per size and backend, so peak
# RSS is per size. Prints and writes a CSV: triangles, backend, wall s, peak RSS MB, scene upload
# ms and GPU MiB, compute BVH ms (flat tree) and bytes, first-frame GPU ms of the G-buffer.
# The BVH cache is off (every size builds). Usage: bench/scale.sh [OUT.csv] [WxH] [MAX_CELLS]
set -euo pipefail
cd "$(dirname "$0")/.."
csv=${1:-/dev/null}
size=${2:-320x180}
max_cells=${3:-1414}
bin=${HYBRID_RT:-target/debug/hybrid-rt}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "triangles,backend,wall_s,peak_rss_mb,upload_ms,scene_gpu_mib,bvh_ms,bvh_bytes,gbuffer_ms" | tee "$csv"
for cells in 71 224 500 707 1000 1414 2236; do
  [ "$cells" -le "$max_cells" ] || continue
  scene=$work/terrain_$cells.toml
  sed "s/^cells = .*/cells = $cells/" bench/scenes/terrain_4m.toml > "$scene"
  for backend in compute query; do
    log=$(HYBRID_RT_BVH_CACHE=off /usr/bin/time -v "$bin" render --scene "$scene" --backend "$backend" \
      --width "${size%x*}" --height "${size#*x}" --out "$work/out.png" --log info 2>&1)
    tris=$(echo "$log" | grep -o 'uploaded scene: [0-9]* triangles' | grep -o '[0-9]*' | head -1)
    wall=$(echo "$log" | grep 'Elapsed (wall clock)' | awk '{print $NF}' | awk -F: '{print $(NF-1)*60 + $NF}')
    rss=$(echo "$log" | grep 'Maximum resident' | awk '{printf "%.0f", $NF / 1024}')
    upload=$(echo "$log" | grep -o 'GPU memory, [0-9.]* ms' | grep -o '[0-9.]* ms' | grep -o '[0-9.]*' | head -1)
    gpu_mib=$(echo "$log" | grep -o '[0-9.]* MiB GPU memory' | grep -o '^[0-9.]*' | head -1)
    bvh_ms=$(echo "$log" | grep -o 'built in [0-9]* ms' | grep -o '[0-9]*' | head -1 || true)
    bvh_bytes=$(echo "$log" | grep -o 'flat triangles = [0-9]* B' | grep -o '[0-9]*' | head -1 || true)
    gbuffer=$(echo "$log" | grep -o 'gbuffer [0-9.]* ms' | grep -o '[0-9.]*' | head -1)
    echo "$tris,$backend,$wall,$rss,$upload,$gpu_mib,${bvh_ms:-},${bvh_bytes:-},$gbuffer" | tee -a "$csv"
  done
done
