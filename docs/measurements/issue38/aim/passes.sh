#!/usr/bin/env bash
# Issue 38, photons aimed at what casts caustics (--caustic-photons S): equal passes and one seed, the
# share S against 0 (every photon by the cosine), on the scenes whose mirrors, glass or rough lobes cast
# light: glass-on-table (the torus's foot) and cornell-spheres (its caustic). Prints the relMSE against
# each reference, whole and per region, and the mean wall time of a pass; writes passes.txt beside this
# script.
# Usage: docs/measurements/issue38/aim/passes.sh [SHARES...]   (default 0 0.5)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
o=docs/measurements/issue38/aim
bin=${BIN:-target/release/ppm-vk}
refs=scenes/references
SHARES=("${@:-0 0.5}")
# name|scene and its options|reference|passes|regions
SCENES=(
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|$refs/glass-on-table.exr|24|torus:80,110,96,40"
  "cornell-spheres|scenes/cornell-spheres.toml --resolution 256x256|../shared/reference/cornell-spheres.exr|24|"
)
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  for entry in "${SCENES[@]}"; do
    IFS='|' read -r name scene ref passes regions <<<"$entry"
    rr=(); for r in $regions; do rr+=(--region "$r"); done
    # shellcheck disable=SC2068
    for s in ${SHARES[@]}; do
      # shellcheck disable=SC2086
      log=$("$bin" render $scene --passes "$passes" --caustic-photons "$s" --reference "$ref" "${rr[@]}" \
        --profile --out "/tmp/aim-$name-$s.exr" --force 2>&1 | grep -v '^warning')
      wall=$(grep -o 'wall [0-9.]*' <<<"$log" | head -1 | grep -o '[0-9.]*$')
      errs=$(grep -E 'relMSE' <<<"$log" | sed -E 's/.*(region [a-z_]+|error vs reference).*relMSE ([0-9.e-]+).*/\1 \2/' | tr '\n' ';')
      echo "$name caustic-photons $s: wall $wall ms a pass; $errs"
    done
  done
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$o/passes.txt"
