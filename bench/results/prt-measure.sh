#!/bin/bash
# Run from the repository root after `cargo build`; writes to /tmp/prt-out.
BIN=${CARGO_TARGET_DIR:-target}/debug/hybrid-rt
mkdir -p /tmp/prt-out
SC=../shared/assets/scenes/SponzaCapsaicin/Sponza.gltf
HDR=$(ls ../shared/assets/hdri/polyhaven_1k/*.hdr | head -1)
export RUST_LOG=info
export HYBRID_RT_PRT_CACHE=/tmp/prt-measure-cache
rm -rf $HYBRID_RT_PRT_CACHE
echo "HDR $HDR"
for m in prt-unshadowed prt-shadowed prt-interreflected; do
  for run in compute load; do
    echo "== $m $run"
    /usr/bin/time -f "wall %e s" $BIN render --scene $SC --env $HDR --width 160 --height 90 --ambient $m --prt-samples 8 --out /tmp/prt-out/sponza-$m.png 2>&1 | grep -E "prt|wall|rror"
  done
done
$BIN render --scene $SC --env $HDR --width 160 --height 90 --ambient sh --out /tmp/prt-out/sponza-sh.png 2>&1 | grep -E "rror"
for m in sh prt-shadowed; do
  echo "== bench $m"
  $BIN bench --scene $SC --env $HDR --width 320 --height 180 --ambient $m --prt-samples 8 --frames 20 --warmup 3 --csv /tmp/prt-out/bench-$m.csv 2>&1 | grep -vE "^\[.*(DEBUG|TRACE)" | tail -30
done
