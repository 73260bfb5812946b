#!/usr/bin/env bash
# Issue 38, the rough splits: the cost of a pass before them (BEFORE_BIN, built from commit 349a0a8 in a
# worktree of its own) and after, in interleaved rounds (the order flipped every round), so the machine's
# drift falls on both alike. cornell-spheres has no rough vertex (the same image bit for bit, the kernels
# differing only in the eye path's branch record); cornell-aniso pays for its 4 slots and its marked pixels.
# Prints one line per render: scene, build, round, the mean GPU ms per stage and the mean wall per pass.
# Usage: BEFORE_BIN=/path/to/old/ppm-vk docs/measurements/issue38/rough-splits/pass-cost.sh [ROUNDS] [PASSES]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
R=${1:-3}
P=${2:-20}
SCENES=(
  "cornell-spheres|scenes/cornell-spheres.toml"
  "cornell-aniso|scenes/references/cornell-aniso.xml -D res=256"
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
