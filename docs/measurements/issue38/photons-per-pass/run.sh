#!/usr/bin/env bash
# Issue 38: photons per pass at equal time. SPPM's eye pass gives each pixel one new sample a pass, so a
# pass of fewer photons buys more eye samples (glossy reflections, anti-aliasing) and faster-shrinking
# radii at the price of fewer photons a pass. Each scene at 1M (the default) and 250k photons a pass,
# SECONDS of passes each, the order flipped from scene to scene. Writes NAME-PHOTONS/ (compare's output).
# Usage: docs/measurements/issue38/photons-per-pass/run.sh [SECONDS] [scene ...]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
T=${1:-30}
shift || true
o=docs/measurements/issue38/photons-per-pass
refs=scenes/references
SCENES=(
  "cornell-aniso|$refs/cornell-aniso.xml -D res=256|$refs/cornell-aniso.exr|gold:40,120,90,90 glass:100,140,90,90"
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|$refs/glass-on-table.exr|torus:80,110,96,40"
  "cornell-box|scenes/cornell-box.toml --resolution 256x256|$refs/cornell-box.exr|"
  "cornell-rough|$refs/cornell-rough.xml -D res=256|$refs/cornell-rough.exr|"
  "cornell-coated|$refs/cornell-coated.xml -D res=256|$refs/cornell-coated.exr|"
  "cornell-spheres|scenes/cornell-spheres.toml|../shared/reference/cornell-spheres.exr|"
)
i=0
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene ref regions <<<"$entry"
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  if [ $((i % 2)) -eq 0 ]; then order="1000000 250000"; else order="250000 1000000"; fi
  i=$((i + 1))
  rg=(); for r in $regions; do rg+=(--region "$r"); done
  for pp in $order; do
    # shellcheck disable=SC2086
    target/release/ppm-vk compare $scene --reference "$ref" --time "$T" --variants sppm --photons-per-pass "$pp" \
      "${rg[@]}" --out "$o/$name-$pp" > "$o/$name-$pp.log" 2>&1
    echo "$name $pp $(grep '^| sppm' "$o/$name-$pp/compare.md")"
  done
done
