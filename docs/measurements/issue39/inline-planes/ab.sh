#!/usr/bin/env bash
# A small mesh's triangles tested by their planes (geometry.glsl's inline_triangle_test) against the build
# before, which tested them with the BVH's watertight test: ROUNDS rounds, the order flipped each round,
# SCENE at its resolution, PASSES passes of `render --profile`; prints each run's mean GPU ms per stage
# and the median eye pass (the ray column of passes 2 on; pass 1's is part of the set-up).
# Usage: BEFORE_BIN=<ppm-vk of the build before> AFTER_BIN=target/release/ppm-vk \
#   docs/measurements/issue39/inline-planes/ab.sh SCENE [ROUNDS] [PASSES]
set -euo pipefail
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
scene=$1
rounds=${2:-3}
passes=${3:-6}
out=$(mktemp -d)
for r in $(seq 1 "$rounds"); do
  order="BEFORE AFTER"
  [ $((r % 2)) -eq 0 ] && order="AFTER BEFORE"
  for which in $order; do
    bin=BEFORE_BIN; [ "$which" = AFTER ] && bin=AFTER_BIN
    log=$("${!bin}" render "$scene" --passes "$passes" --profile --force --out "$out/$which.exr" 2>&1)
    eye=$(echo "$log" | awk '$1 ~ /^[0-9]+$/ && $1 >= 2 {print $3}' | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
    echo "$which round $r: $(echo "$log" | grep 'mean GPU ms per pass') | eye pass median $eye"
  done
done
rm -rf "$out"
