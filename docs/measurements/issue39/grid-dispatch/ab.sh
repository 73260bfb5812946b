#!/usr/bin/env bash
# The grid build's dispatches sized by the records (grid_dispatch.comp) against the build that sized them
# by the buffer's capacity: ROUNDS rounds, the order flipped each round, SCENE at its resolution, PASSES
# passes of `render --profile`; prints each run's mean GPU ms per stage and wall per pass.
# Usage: BEFORE_BIN=<ppm-vk of the build before> AFTER_BIN=target/release/ppm-vk \
#   docs/measurements/issue39/grid-dispatch/ab.sh SCENE [ROUNDS] [PASSES] [render flags ...]
set -euo pipefail
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
scene=$1
rounds=${2:-3}
passes=${3:-8}
shift 3 || shift $#
out=$(mktemp -d)
for r in $(seq 1 "$rounds"); do
  order="BEFORE AFTER"
  [ $((r % 2)) -eq 0 ] && order="AFTER BEFORE"
  for which in $order; do
    bin=BEFORE_BIN; [ "$which" = AFTER ] && bin=AFTER_BIN
    printf '%s round %s: ' "$which" "$r"
    "${!bin}" render "$scene" --passes "$passes" --profile --force --out "$out/$which.exr" "$@" 2>&1 \
      | grep 'mean GPU ms per pass'
  done
  cmp -s "$out/BEFORE.exr" "$out/AFTER.exr" && echo "round $r: the images are the same, bit for bit" \
    || echo "round $r: the images differ"
done
rm -rf "$out"
