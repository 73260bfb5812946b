#!/usr/bin/env bash
# Issue 38, what the adaptive shrink keeps of the gathered statistics: the fit's share N(p) / N(R)
# (this build) against the area's share (p / R)^2 (BEFORE_BIN, the build before), at equal passes and one
# seed (the same photons until the radii part): glass-on-table (48 passes, 256^2, its torus's foot),
# cornell-spheres (32 passes, 512^2), cornell-box (24 passes, 256^2), spot-caustic (32 passes, 128^2).
# Usage: BEFORE_BIN=path/to/old/ppm-vk docs/measurements/issue38/shrink-history/run.sh (from the
# repository root)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
o=docs/measurements/issue38/shrink-history
refs=scenes/references
# name | scene and flags | passes | reference | regions
SCENES=(
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|48|$refs/glass-on-table.exr|--region torus:80,110,96,40"
  "cornell-spheres|scenes/cornell-spheres.toml|32|../shared/reference/cornell-spheres.exr|--region caustic:250,436,70,40"
  "cornell-box|scenes/cornell-box.toml --resolution 256x256|24|$refs/cornell-box.exr|"
  "spot-caustic|scenes/spot-caustic.xml -D res=128|32|$refs/spot-caustic.exr|"
)
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene passes ref regions <<<"$entry"
  for v in before after; do
    bin=target/release/ppm-vk
    [ "$v" = before ] && bin=$BEFORE_BIN
    # shellcheck disable=SC2086
    "$bin" render $scene --passes "$passes" --reference "$ref" $regions \
      -o "/tmp/shrink-history-$name-$v.exr" -f > "$o/$name-$v.txt" 2>&1
    echo "$name $v: $(grep 'relMSE' "$o/$name-$v.txt" | tr -s ' ' | paste -sd';')"
  done
done
