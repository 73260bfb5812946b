#!/usr/bin/env bash
# Issue 39: what the default curvature probe (issue 38) adds to a warm set-up: the interior at 320x180 and
# cornell-spheres, eq. 8's radius (--probe off) against the default, two interleaved rounds, caches warm
# (run once before). Prints each render's set-up line.
# Usage: docs/measurements/issue39/setup-probe/run.sh > docs/measurements/issue39/setup-probe/setup.txt
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
for scene in "scenes/interior.xml -D width=320 -D height=180" "scenes/cornell-spheres.toml"; do
  # shellcheck disable=SC2086
  target/release/ppm-vk render $scene --passes 1 --profile -o /tmp/setup-probe.exr -f > /dev/null 2>&1 # warm the caches
  for r in 1 2; do
    if [ "$r" = 1 ]; then order="off curvature"; else order="curvature off"; fi
    for p in $order; do
      # shellcheck disable=SC2086
      echo "${scene%% *} --probe $p round $r: $(target/release/ppm-vk render $scene --passes 1 --probe $p --profile \
        -o /tmp/setup-probe.exr -f 2>&1 | grep '^set-up')"
    done
  done
done
