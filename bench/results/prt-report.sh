#!/bin/bash
# `report --prt` runs behind bench/results/report/prt_*/ (issue 15 item 7).
# Run from the repository root after `cargo build` (BIN may point at a copy
# of the binary). Sequential: the machine is shared.
BIN=${BIN:-${CARGO_TARGET_DIR:-target}/debug/hybrid-rt}
OUT=bench/results/report
HDRI=../shared/assets/hdri/polyhaven_1k
export HYBRID_RT_PRT_CACHE=${HYBRID_RT_PRT_CACHE:-/tmp/prtrep-report-cache}
SPONZA="--scene ../shared/assets/scenes/SponzaCapsaicin/Sponza.gltf --look-from 12,5.7,0 --look-at -10,5,0 --fov 60"
COMMON="--width 160 --height 90 --frames 5 --warmup 1 --prt-samples 8"
run() { # name, args...
  local name=$1; shift
  echo "== $name $(date -u +%T) load $(cut -d' ' -f1-3 /proc/loadavg)"
  /usr/bin/time -f "$name: wall %e s, user %U s" $BIN report --prt $COMMON "$@" --out $OUT/$name 2>&1 \
    | grep -E "report --prt|wall|rror|warn" | grep -v "reference frame"
}
[ "$1" = sweeps ] && SKIP=1
# The full product (5 bands x 4 projections x 5 transfers, sh at 3 bands only).
[ -z "$SKIP" ] && run prt_helmet_venice_sunset --scene ../shared/assets/gltf/DamagedHelmet/glTF/DamagedHelmet.gltf \
  --look-from 0.6,0.3,2.6 --look-at 0,0,0 --fov 45 \
  --env $HDRI/venice_sunset_1k.hdr --reference-samples 1024 --reference-bounces 3
# Sponza: bands x transfer at the exact projection under one map ...
[ -z "$SKIP" ] && run prt_sponza_empty_warehouse_grid $SPONZA --env $HDRI/empty_warehouse_01_1k.hdr \
  --knobs bands,transfer=sh:prt-unshadowed:prt-shadowed:prt-interreflected-1,sh-samples=exact \
  --reference-samples 256 --reference-bounces 3
# ... and one knob at a time around prt-shadowed / 3 bands / exact under every
# map (prt-interreflected-2 left out and 128 reference samples: the machine
# was loaded ~13 at the time, the grid above took its precompute budget).
[ "$1" = grid-only ] && exit 0
for map in assets/potsdamer_platz_512.hdr $HDRI/empty_warehouse_01_1k.hdr $HDRI/venice_sunset_1k.hdr \
  $HDRI/studio_small_03_1k.hdr $HDRI/st_fagans_interior_1k.hdr $HDRI/potsdamer_platz_1k.hdr; do
  name=$(basename $map .hdr); name=${name%_1k}; name=${name%_01}
  run prt_sponza_$name $SPONZA --env $map --ambient prt-shadowed --prt-sweep \
    --knobs transfer=sh:prt-unshadowed:prt-shadowed:prt-interreflected-1,bands,sh-samples \
    --reference-samples 128 --reference-bounces 3
done
echo "== done $(date -u +%T) load $(cut -d' ' -f1-3 /proc/loadavg)"
