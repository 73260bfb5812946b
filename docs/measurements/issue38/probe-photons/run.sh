#!/usr/bin/env bash
# Issue 38: how many probe photons the curvature rule wants, on glass-on-table's narrow caustic: 48 passes
# of 1M photons at 256^2 with the probe given 0.25M to 4M photons (the default is one pass's, 1M).
# Usage: docs/measurements/issue38/probe-photons/run.sh > docs/measurements/issue38/probe-photons/glass-on-table.txt
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
for pp in 250000 500000 1000000 2000000 4000000; do
  echo "== --probe-photons $pp"
  target/release/ppm-vk render scenes/glass-on-table.toml --resolution 256x256 --passes 48 --probe curvature \
    --probe-photons "$pp" --reference scenes/references/glass-on-table.exr --region torus:80,110,96,40 \
    -o /tmp/probe-photons.exr -f 2>&1 | grep -E "relMSE|probe:|set-up"
done
