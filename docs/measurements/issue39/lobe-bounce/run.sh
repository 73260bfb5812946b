#!/usr/bin/env bash
# Issue 39: the photon kernel's plastics, rough conductors and rough glass sampled in one routine
# (photon/lobe_bounce.glsl) against the build before (BEFORE_BIN: a sampler per surface). Two bench rounds,
# the order flipped in the second, over cornell-spheres (no such surface), the interior (rough plastic and
# rough metal), cornell-roughplastic, cornell-aniso (rough metal and glass) and cornell-coated (smooth
# plastic). Writes bench-{before,after}-ROUND.{json,txt} beside this script.
# Usage: BEFORE_BIN=/tmp/ppm-vk-base docs/measurements/issue39/lobe-bounce/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."
out=docs/measurements/issue39/lobe-bounce
bench() {
  "$1" bench --scene scenes/cornell-spheres.toml --scene scenes/interior.xml --scene scenes/references/cornell-roughplastic.xml --scene scenes/references/cornell-aniso.xml --scene scenes/references/cornell-coated.xml \
    --cases 1M@512x512 --warmup 1 --passes 3 --json "$out/bench-$2.json" 2>&1 | tee "$out/bench-$2.txt"
}
for round in 1 2; do
  if [ "$round" = 1 ]; then order="before after"; else order="after before"; fi
  for b in $order; do
    if [ "$b" = before ]; then bin=$BEFORE_BIN; else bin=target/release/ppm-vk; fi
    echo "== $b, round $round ($(uptime))"
    bench "$bin" "$b-$round"
  done
done
