#!/usr/bin/env bash
# Issue 38: eq. 8's radius against the curvature probe capped to shrink (`--probe curvature`, probe_grow 1)
# at equal passes on every scene with a reference: the error a pass buys, apart from what a pass costs
# (for that, ../pass-cost/run.sh). Writes NAME-VARIANT.txt (render's report: relMSE whole and per region).
# Usage: docs/measurements/issue38/equal-passes-shrink/run.sh [PASSES] [scene ...]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
P=${1:-48}
shift || true
o=docs/measurements/issue38/equal-passes-shrink
refs=scenes/references
# name | scene and flags | reference | regions (render --region NAME:X,Y,W,H)
SCENES=(
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|$refs/glass-on-table.exr|--region torus:80,110,96,40"
  "cornell-spheres|scenes/cornell-spheres.toml|../shared/reference/cornell-spheres.exr|"
  "cornell-aniso|$refs/cornell-aniso.xml -D res=256|$refs/cornell-aniso.exr|--region gold:40,120,90,90 --region glass:100,140,90,90"
  "cornell-rough|$refs/cornell-rough.xml -D res=256|$refs/cornell-rough.exr|"
  "cornell-smooth|$refs/cornell-smooth.xml -D res=256|$refs/cornell-smooth.exr|"
  "cornell-coated|$refs/cornell-coated.xml -D res=256|$refs/cornell-coated.exr|"
  "cornell-gold|$refs/cornell-gold.xml -D res=256|$refs/cornell-gold.exr|"
  "cornell-box|scenes/cornell-box.toml --resolution 256x256|$refs/cornell-box.exr|"
)
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene ref regions <<<"$entry"
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  for v in off curvature; do
    # shellcheck disable=SC2086
    target/release/ppm-vk render $scene --passes "$P" --probe "$v" --reference "$ref" $regions \
      -o "/tmp/eqp-$name-$v.exr" -f > "$o/$name-$v.txt" 2>&1
    echo "$name $v: $(grep 'relMSE' "$o/$name-$v.txt" | head -1)"
  done
done
