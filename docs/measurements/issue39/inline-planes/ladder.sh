#!/usr/bin/env bash
# Issue 39's ladder, the build before (BEFORE_BIN) and after (AFTER_BIN) a small mesh's triangles were
# tested by their planes, with cornell-box (the default scene) beside them: one bench run each, 1M photons at 512x512, as docs/performance.md's ladders.
# Usage: BEFORE_BIN=... AFTER_BIN=target/release/ppm-vk docs/measurements/issue39/inline-planes/ladder.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
o=docs/measurements/issue39/inline-planes
for which in BEFORE AFTER; do
  bin=${which}_BIN
  "${!bin}" bench --scene scenes/cornell-spheres.toml --scene scenes/cornell-mesh.toml \
    --scene scenes/glass-on-table.toml --scene scenes/cornell-dense.toml --scene scenes/interior.xml --scene scenes/cornell-box.toml \
    --cases 1M@512x512 --warmup 1 --passes 3 --json "$o/ladder-${which,,}.json" > "$o/ladder-${which,,}.txt" 2>&1
done
