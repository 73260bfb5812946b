#!/usr/bin/env bash
# Issue 39: the eye pass with one traversal per shadow ray a vertex may send (ShadowRay in ray.comp) against
# the build before it (one traversal per kind of vertex that sends one). Two rounds, the order flipped in
# the second, each build one bench run over the mesh ladder and two scenes of rough vertices and coats;
# ratios are read within a run, the builds compared round by round. BEFORE_BIN: the build before (built from
# the parent commit); writes NAME-{before,after}-ROUND.{json,txt} beside this script.
# Usage: BEFORE_BIN=/tmp/ppm-vk-base docs/measurements/issue39/shadow-sites/run.sh [NAME]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
out=docs/measurements/issue39/shadow-sites
name=${1:-bench}
bench() {
  "$1" bench --scene scenes/cornell-spheres.toml --scene scenes/cornell-mesh.toml \
    --scene scenes/glass-on-table.toml --scene scenes/cornell-dense.toml --scene scenes/interior.xml \
    --scene scenes/references/cornell-aniso.xml --scene scenes/references/cornell-roughplastic.xml \
    --cases 1M@512x512 --warmup 1 --passes 3 --json "$out/$name-$2.json" 2>&1 | tee "$out/$name-$2.txt"
}
for round in 1 2; do
  if [ "$round" = 1 ]; then order="before after"; else order="after before"; fi
  for b in $order; do
    if [ "$b" = before ]; then bin=$BEFORE_BIN; else bin=target/release/ppm-vk; fi
    echo "== $b, round $round ($(uptime))"
    bench "$bin" "$b-$round"
  done
done
