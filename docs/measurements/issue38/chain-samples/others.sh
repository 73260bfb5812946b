#!/usr/bin/env bash
# Issue 38, chains that pass near a light (MARK_NEAR): the pixels whose pilot chain left a curved mirror or
# glass and passed within twice a light's bounding radius take every emission sample. Equal passes, the
# same seeds for both builds: BASE (the build before, 43164da) and NEW (this change), so the two differ only
# in the marks. Prints per scene, build and seed the pilot's marks, its time, the mean wall time of a pass
# and the relMSE (the scene's region in brackets); writes others.txt beside this (or OUT=FILE).
# glass-on-table has its own script (seeds.sh).
# Usage: BASE=path NEW=path docs/measurements/issue38/chain-samples/others.sh [scene ...]  (from the
# repository root)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
o=docs/measurements/issue38/chain-samples
refs=scenes/references
out=${OUT:-$o/others.txt}
# name|scene and its options|reference|passes|seeds|regions
SCENES=(
  "cornell-spheres|scenes/cornell-spheres.toml|../shared/reference/cornell-spheres.exr|32|0 1|"
  "cornell-smooth|$refs/cornell-smooth.xml -D res=256|$refs/cornell-smooth.exr|48|0 1|"
  "cornell-gold|$refs/cornell-gold.xml -D res=256|$refs/cornell-gold.exr|48|0 1|"
  "interior|scenes/interior.xml -D width=160 -D height=90 --photons-per-pass 200000|$refs/interior.exr|24|0 1|"
)
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  echo "| scene | build | seed | marks (emission, near a light, rough, lit; all samples) | pilot s | wall ms a pass | relMSE (region) |"
  echo "|---|---|---|---|---|---|---|"
  for entry in "${SCENES[@]}"; do
    IFS='|' read -r name scene ref passes seeds regions <<<"$entry"
    if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
    for seed in $seeds; do
      for build in BASE NEW; do
        bin=${!build}
        # shellcheck disable=SC2086
        log=$("$bin" render $scene --passes "$passes" --seed "$seed" --reference "$ref" $regions --profile \
          --out "/tmp/chain-samples-$name-$build-$seed.exr" --force 2>&1 | grep -v '^warning')
        marks=$(grep -o 'emission [0-9.]*%.*lit [0-9.]*%\|all emission samples in [0-9.]*%' <<<"$log" | paste -sd';')
        pilot=$(grep -o 'pilot eye pass [0-9.]*' <<<"$log" | grep -o '[0-9.]*$')
        wall=$(grep -o 'wall [0-9.]*' <<<"$log" | head -1 | grep -o '[0-9.]*$')
        rel=$(grep -o 'relMSE [0-9.e-]*' <<<"$log" | grep -o '[0-9.e-]*$' | paste -sd' ')
        echo "| $name | $build | $seed | $marks | $pilot | $wall | $rel |"
      done
    done
  done
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$out"
