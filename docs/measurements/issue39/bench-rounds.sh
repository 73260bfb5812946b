#!/usr/bin/env bash
# Issue 39: a change against the build before it, by bench runs in two rounds, the order flipped in the
# second (ratios are read within a run, the builds compared round by round): 1M photons at 512x512, one
# warm-up pass and three timed, over the scenes given. BEFORE_BIN: the build before; AFTER_BIN: the build
# after (default target/release/ppm-vk). Writes OUT/NAME-{before,after}-ROUND.{json,txt}.
# Usage: BEFORE_BIN=/tmp/ppm-vk-base docs/measurements/issue39/bench-rounds.sh OUT NAME SCENE...
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=$1
name=$2
shift 2
scenes=()
for s in "$@"; do scenes+=(--scene "$s"); done
for round in 1 2; do
  if [ "$round" = 1 ]; then order="before after"; else order="after before"; fi
  for b in $order; do
    if [ "$b" = before ]; then bin=$BEFORE_BIN; else bin=${AFTER_BIN:-target/release/ppm-vk}; fi
    echo "== $b, round $round ($(uptime))"
    "$bin" bench "${scenes[@]}" --cases 1M@512x512 --warmup 1 --passes 3 --json "$out/$name-$b-$round.json" 2>&1 \
      | tee "$out/$name-$b-$round.txt"
  done
done
