#!/usr/bin/env bash
# The light samples taken on the hit-point path (issue 39): BEFORE_BIN and AFTER_BIN (default
# target/release/ppm-vk) given the same seconds of passes (`compare --time`, set-up excluded) on every scene
# with a reference, one after the other scene by scene (the same hour for both), the default settings.
# Prints each run's compare table; OUT=DIR keeps the runs (default /tmp/hit-path-shadows).
# Usage: BEFORE_BIN=/tmp/ppm-vk-before docs/measurements/issue39/hit-path-shadows/equal-time.sh [SECONDS] [scene ...]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
T=${1:-30}
shift || true
o=${OUT:-/tmp/hit-path-shadows}
after=${AFTER_BIN:-target/release/ppm-vk}
mkdir -p "$o"
refs=scenes/references
# name | scene and flags | reference | compare regions
SCENES=(
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|$refs/glass-on-table.exr|torus:80,110,96,40"
  "cornell-spheres|scenes/cornell-spheres.toml|../shared/reference/cornell-spheres.exr|"
  "cornell-box|scenes/cornell-box.toml --resolution 256x256|$refs/cornell-box.exr|"
  "cornell-coated|$refs/cornell-coated.xml -D res=256|$refs/cornell-coated.exr|"
  "cornell-aniso|$refs/cornell-aniso.xml -D res=256|$refs/cornell-aniso.exr|gold:40,120,90,90 glass:100,140,90,90"
  "cornell-rough|$refs/cornell-rough.xml -D res=256|$refs/cornell-rough.exr|"
  "cornell-smooth|$refs/cornell-smooth.xml -D res=256|$refs/cornell-smooth.exr|"
  "cornell-gold|$refs/cornell-gold.xml -D res=256|$refs/cornell-gold.exr|"
)
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene ref regions <<<"$entry"
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  cr=(); for r in $regions; do cr+=(--region "$r"); done
  for b in before after; do
    bin=$BEFORE_BIN
    [ "$b" = after ] && bin=$after
    # shellcheck disable=SC2086
    "$bin" compare $scene --reference "$ref" --time "$T" --variants sppm "${cr[@]}" --out "$o/$name-$b" \
      > "$o/$name-$b.log" 2>&1
    echo "== $name $b $(date -u +%H:%M:%S)"
    grep '^|' "$o/$name-$b/compare.md" | tail -n 1
  done
done
