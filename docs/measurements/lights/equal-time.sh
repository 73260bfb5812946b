#!/bin/sh
# Equal-time error against Mitsuba 3's path tracer on the two new scenes (issue 36), both renderers
# timed in one run on this machine: ppm-vk's sppm for 30 s, then Mitsuba's path tracer at the spp that
# take 30 s here (docs/peers/mitsuba_equal_time.py), two runs.
set -e
cd "$(dirname "$0")/../../.."
OUT=docs/measurements/lights
for s in spot-caustic env-window; do
  ./target/release/ppm-vk compare scenes/$s.xml --reference scenes/references/$s.exr --time 30 \
    --variants "sppm" --photons-per-pass 200000 --out $OUT/$s-30s
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 docs/peers/mitsuba_equal_time.py \
    scenes/$s.xml scenes/references/$s.exr --seconds 30 --runs 2 > $OUT/$s-mitsuba-30s.txt
done
