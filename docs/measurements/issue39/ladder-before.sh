#!/usr/bin/env bash
# The interior and the mesh ladder before any change (issue 39): one bench run, ratios to cornell-spheres
# within the run; writes NAME.json and the printed table NAME.txt beside this script (NAME: the first
# argument, default ladder-before).
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/measurements/issue39
name=${1:-ladder-before}
target/release/ppm-vk bench --scene scenes/cornell-spheres.toml --scene scenes/cornell-mesh.toml \
  --scene scenes/glass-on-table.toml --scene scenes/cornell-dense.toml --scene scenes/interior.xml \
  --cases 1M@512x512 --warmup 1 --passes 3 --breakdown --json $out/$name.json 2>&1 | tee $out/$name.txt
