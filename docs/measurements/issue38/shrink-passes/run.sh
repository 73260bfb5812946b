#!/usr/bin/env bash
# Issue 38, the adaptive shrink's threshold at equal passes (deterministic: one seed, the same photons):
# --shrink-z 0 (off), 1, 2 (the default) and 3 on glass-on-table (48 passes, 256^2), where the radius's
# bias dominates, and on cornell-spheres (32 passes, 512^2) and cornell-box (24 passes, 256^2), where
# noise does. Writes NAME-zZ.txt (render's report) and prints the relMSE lines.
# Usage: docs/measurements/issue38/shrink-passes/run.sh (from the repository root)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
o=docs/measurements/issue38/shrink-passes
refs=scenes/references
# name | scene and flags | passes | reference | regions
SCENES=(
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|48|$refs/glass-on-table.exr|--region torus:80,110,96,40"
  "cornell-spheres|scenes/cornell-spheres.toml|32|../shared/reference/cornell-spheres.exr|"
  "cornell-box|scenes/cornell-box.toml --resolution 256x256|24|$refs/cornell-box.exr|"
)
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene passes ref regions <<<"$entry"
  for z in 0 1 2 3; do
    # shellcheck disable=SC2086
    target/release/ppm-vk render $scene --passes "$passes" --shrink-z $z --reference "$ref" $regions \
      -o "/tmp/shrink-passes-$name-$z.exr" -f > "$o/$name-z$z.txt" 2>&1
    echo "$name --shrink-z $z: $(grep 'relMSE' "$o/$name-z$z.txt" | tr -s ' ' | paste -sd';')"
  done
done
