#!/usr/bin/env bash
# Issue 39: kernels specialised to the microfacet distributions a scene uses (SCENE_GGX, SCENE_BECKMANN in
# microfacet.glsl) against the build before (BEFORE_BIN, both distributions' code in every kernel). Two
# bench rounds, the order flipped in the second, over cornell-spheres (no rough surface: unchanged) and the
# interior (GGX only); then the interior's set-up, cold and warm (../shadow-sites/setup.sh). Writes
# bench-{before,after}-ROUND.{json,txt} and setup.txt beside this script.
# Usage: BEFORE_BIN=/tmp/ppm-vk-base docs/measurements/issue39/microfacet-kinds/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."
out=docs/measurements/issue39/microfacet-kinds
bench() {
  "$1" bench --scene scenes/cornell-spheres.toml --scene scenes/interior.xml \
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
docs/measurements/issue39/shadow-sites/setup.sh | tee "$out/setup.txt"
