#!/usr/bin/env bash
# Issue 39, the pilot's samples (--pilot-samples): what fewer cost in the image. Equal passes and one seed,
# so each variant differs only in the marks its pilot made (which pixels take --emission-samples, which
# are lit); the scenes where a light, or its image through glass, is in view: glowing-spheres (a sphere 1-2
# pixels wide), textured-light, cornell-spheres and glass-on-table (the light through glass), cornell-aniso
# (the rough marks), the interior (13 lamps) and penumbra. Prints, per scene and count, the pilot's marks,
# its time, the mean wall time of a pass and the relMSE against the reference; writes run.txt beside this.
# Usage: docs/measurements/issue39/pilot/run.sh [COUNTS...]   (default 16 8 4 2)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
o=docs/measurements/issue39/pilot
bin=${BIN:-target/release/ppm-vk}
refs=scenes/references
COUNTS=("${@:-16 8 4 2}")
# name|scene and its options|reference|passes
SCENES=(
  "glowing-spheres|scenes/glowing-spheres.xml|$refs/glowing-spheres.exr|32"
  "textured-light|scenes/textured-light.xml|$refs/textured-light.exr|32"
  "cornell-spheres|scenes/cornell-spheres.toml --resolution 256x256|../shared/reference/cornell-spheres.exr|24"
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|$refs/glass-on-table.exr|24"
  "cornell-aniso|$refs/cornell-aniso.xml -D res=256|$refs/cornell-aniso.exr|12"
  "interior|scenes/interior.xml -D width=160 -D height=90 --photons-per-pass 200000|$refs/interior.exr|24"
  "penumbra|$refs/penumbra.xml -D res=256|$refs/penumbra.exr|24"
)
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  echo "| scene | pilot samples | marks (emission, rough, lit) | pilot s | wall ms a pass | relMSE |"
  echo "|---|---|---|---|---|---|"
  for entry in "${SCENES[@]}"; do
    IFS='|' read -r name scene ref passes <<<"$entry"
    # shellcheck disable=SC2068
    for n in ${COUNTS[@]}; do
      # shellcheck disable=SC2086
      log=$("$bin" render $scene --passes "$passes" --pilot-samples "$n" --reference "$ref" --profile \
        --out "/tmp/pilot-$name-$n.exr" --force 2>&1 | grep -v '^warning')
      marks=$(grep -o 'emission [0-9.]*%, rough [0-9.]*%, lit [0-9.]*%' <<<"$log")
      pilot=$(grep -o 'pilot eye pass [0-9.]*' <<<"$log" | grep -o '[0-9.]*$')
      wall=$(grep -o 'wall [0-9.]*' <<<"$log" | head -1 | grep -o '[0-9.]*$')
      rel=$(grep -o 'relMSE [0-9.e-]*' <<<"$log" | tail -1 | grep -o '[0-9.e-]*$')
      echo "| $name | $n | $marks | $pilot | $wall | $rel |"
    done
  done
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$o/run.txt"
