#!/usr/bin/env bash
# Issue 38, the adaptive shrink: the cost of a pass before it (BEFORE_BIN, the binary of commit 29b93a2)
# and after, in interleaved rounds (the order flipped every round), so the machine's drift falls on both
# alike. The gather now also counts the photons within R / 2 and the update fits the curvature; on
# cornell-spheres the shrink barely acts, on glass-on-table it shrinks the caustic's radii.
# Prints one line per render: scene, build, round, the mean GPU ms per stage and the mean wall per pass.
# Usage: BEFORE_BIN=/path/to/old/ppm-vk docs/measurements/issue38/shrink-60s/pass-cost.sh [ROUNDS] [PASSES]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
R=${1:-4}
P=${2:-20}
SCENES=(
  "cornell-spheres|scenes/cornell-spheres.toml"
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256"
)
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene <<<"$entry"
  for r in $(seq 1 "$R"); do
    if [ $((r % 2)) -eq 1 ]; then order="before after"; else order="after before"; fi
    for v in $order; do
      bin=target/release/ppm-vk
      [ "$v" = before ] && bin=$BEFORE_BIN
      # shellcheck disable=SC2086
      line=$("$bin" render $scene --passes "$P" --profile -o /tmp/pass-cost.exr -f 2>&1 | grep 'mean GPU ms per pass')
      echo "$name $v round $r: ${line#mean GPU ms per pass: }"
    done
  done
done
