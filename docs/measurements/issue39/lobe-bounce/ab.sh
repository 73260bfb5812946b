#!/usr/bin/env bash
# Issue 39: the photon stage and the eye pass of BEFORE_BIN and AFTER_BIN (default target/release/ppm-vk),
# `render --profile` of 500k photons a pass, 4 passes a run, the builds alternated ROUNDS times; prints the
# least time of passes 2-4 over all runs of each build (the least is the run the machine's drift disturbed
# least: this machine's speed moves by 20-40% within an hour).
# Usage: BEFORE_BIN=/tmp/ppm-vk-base ab.sh SCENE RESOLUTION ROUNDS
set -euo pipefail
cd "$(dirname "$0")/../../../.."
scene=$1
res=$2
rounds=$3
after=${AFTER_BIN:-target/release/ppm-vk}
for r in $(seq "$rounds"); do
  for b in before after; do
    bin=$BEFORE_BIN
    [ "$b" = after ] && bin=$after
    "$bin" render "$scene" --photons-per-pass 500000 --resolution "$res" --profile --passes 4 \
      --out /tmp/lobe-bounce-ab.exr --force 2>&1 | awk -v b="$b" '$1 ~ /^[234]$/ && NF > 8 {print b, $3, $4}'
  done
done | awk -v s="$scene" '{
  if (!($1 in p) || $3 < p[$1]) p[$1] = $3
  if (!($1 in e) || $2 < e[$1]) e[$1] = $2
} END { printf "%s: photon stage %.1f -> %.1f ms (%.3fx), eye pass %.1f -> %.1f ms (%.3fx)\n", s, p["before"], p["after"], p["after"] / p["before"], e["before"], e["after"], e["after"] / e["before"] }'
