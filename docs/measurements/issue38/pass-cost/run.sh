#!/usr/bin/env bash
# Issue 38: the cost of a pass with the curvature probe (shrink only) against eq. 8's radius alone, in
# interleaved rounds (the order flipped every round), so the machine's drift falls on both alike.
# Prints one line per render: scene, variant, round, the mean GPU ms per stage and the mean wall per pass.
# Usage: docs/measurements/issue38/pass-cost/run.sh [ROUNDS] [PASSES]  (from anywhere; needs target/release/ppm-vk)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
R=${1:-3}
P=${2:-20}
SCENES=(
  "cornell-spheres|scenes/cornell-spheres.toml"
  "cornell-box|scenes/cornell-box.toml --resolution 256x256"
  "cornell-rough|scenes/references/cornell-rough.xml -D res=256"
)
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene <<<"$entry"
  for r in $(seq 1 "$R"); do
    if [ $((r % 2)) -eq 1 ]; then order="off curvature"; else order="curvature off"; fi
    for v in $order; do
      # shellcheck disable=SC2086
      line=$(target/release/ppm-vk render $scene --passes "$P" --probe "$v" --profile -o /tmp/pass-cost.exr -f 2>&1 | grep 'mean GPU ms per pass')
      echo "$name $v round $r: ${line#mean GPU ms per pass: }"
    done
  done
done
