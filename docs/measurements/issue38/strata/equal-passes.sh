#!/usr/bin/env bash
# Stratified positions of the emission samples (issue 38): BEFORE_BIN and AFTER_BIN (default
# target/release/ppm-vk) render each scene for the same number of passes with the same seeds, against its
# reference (`render --reference`: RMSE, relMSE, bias, with the reference's own noise removed).
# Usage: BEFORE_BIN=/tmp/ppm-vk-before docs/measurements/issue38/strata/equal-passes.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."
after=${AFTER_BIN:-target/release/ppm-vk}
refs=scenes/references
# scene and flags | reference | passes | seeds
RUNS=(
  "scenes/cornell-box.toml --resolution 256x256|$refs/cornell-box.exr|30|1 2 3"
  "scenes/interior.xml --resolution 160x90|$refs/interior.exr|20|1 2"
  "scenes/cornell-spheres.toml --resolution 512x512|../shared/reference/cornell-spheres.exr|15|1"
  "$refs/cornell-aniso.xml -D res=256 --resolution 256x256|$refs/cornell-aniso.exr|10|1"
  "scenes/glass-on-table.toml --resolution 256x256 --region torus:80,110,96,40|$refs/glass-on-table.exr|30|1 2 3 4"
)
for entry in "${RUNS[@]}"; do
  IFS='|' read -r scene ref passes seeds <<<"$entry"
  for seed in $seeds; do
    for b in before after; do
      bin=$BEFORE_BIN
      [ "$b" = after ] && bin=$after
      # shellcheck disable=SC2086
      echo "$b | $scene | seed $seed | $("$bin" render $scene --passes "$passes" --seed "$seed" --reference "$ref" \
        --out /tmp/strata-equal-passes.exr --force 2>&1 | grep -A1 'error vs' | tr '\n' ' ')"
    done
  done
done
