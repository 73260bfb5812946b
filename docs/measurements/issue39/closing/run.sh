#!/usr/bin/env bash
# Issue 39's closing figures, both builds in one session: the build before any change of issue 39
# (BEFORE_BIN: d89aadf, which added scenes/interior.xml) and the build after (AFTER_BIN).
#  1. The ladder: one bench run per build and round, 1M photons at 512x512, the ratios against
#     cornell-spheres in the same run; two rounds in opposite order (before, after, after, before).
#  2. The interior's set-up at 320x180, 200k photons, one pass: cold (empty ppm-vk and Mesa caches) then
#     warm twice, per build.
# Usage: BEFORE_BIN=... AFTER_BIN=target/release/ppm-vk docs/measurements/issue39/closing/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
o=docs/measurements/issue39/closing
ladder() {
  echo "$2: $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" >> "$o/times.txt"
  "$1" bench --scene scenes/cornell-spheres.toml --scene scenes/cornell-mesh.toml \
    --scene scenes/glass-on-table.toml --scene scenes/cornell-dense.toml --scene scenes/interior.xml \
    --cases 1M@512x512 --warmup 1 --passes 3 --json "$o/$2.json" > "$o/$2.txt" 2>&1
}
: > "$o/times.txt"
ladder "$BEFORE_BIN" ladder-before-1
ladder "$AFTER_BIN" ladder-after-1
ladder "$AFTER_BIN" ladder-after-2
ladder "$BEFORE_BIN" ladder-before-2
for which in BEFORE AFTER; do
  bin=${which}_BIN
  T=$(mktemp -d)
  for run in cold warm1 warm2; do
    echo "setup-${which,,}-$run: $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" >> "$o/times.txt"
    MESA_SHADER_CACHE_DIR=$T/mesa "${!bin}" render scenes/interior.xml --passes 1 --photons-per-pass 200000 \
      --resolution 320x180 --pipeline-cache "$T/ppm" -o "$T/o.exr" -f --profile > "$o/setup-${which,,}-$run.txt" 2>&1
  done
  rm -rf "$T"
done
# 3. Where the after build's time goes: the photon kernel's breakdown (as rendered, without record stores,
#    tracing alone) on cornell-spheres and the interior, one bench run.
echo "breakdown-after: $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" >> "$o/times.txt"
"$AFTER_BIN" bench --scene scenes/cornell-spheres.toml --scene scenes/interior.xml --cases 1M@512x512 \
  --warmup 1 --passes 3 --breakdown --json "$o/breakdown-after.json" > "$o/breakdown-after.txt" 2>&1
