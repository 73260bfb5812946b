#!/usr/bin/env bash
# Issue 38, the pilot's Fresnel branches: the pilot eye pass takes each branch of smooth glass (and of a
# thin pane) with probability 1/2 instead of by Fresnel, so it marks the pixels that show a light reflected
# in glass (ray.comp's branch_u). Equal passes, the same seeds for both builds: BASE (the build before,
# 836a634) and NEW (this change), so the two differ only in the marks. Prints per scene, build and seed the
# pilot's marks, its time, the mean wall time of a pass and the relMSE (the scene's region in brackets);
# writes run.txt beside this (or OUT=FILE).
# Usage: BASE=path NEW=path docs/measurements/issue38/pilot-fresnel/run.sh [scene ...]  (from the repository
# root; builds: `git worktree add /tmp/base 836a634 && cargo build --release` there, and this tree's)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
o=docs/measurements/issue38/pilot-fresnel
refs=scenes/references
out=${OUT:-$o/run.txt}
# name|scene and its options|reference|passes|seeds|regions
SCENES=(
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|$refs/glass-on-table.exr|140|0 1 2 3 4 5 6|--region torus:80,110,96,40"
  "cornell-spheres|scenes/cornell-spheres.toml|../shared/reference/cornell-spheres.exr|32|0 1|"
  "cornell-smooth|$refs/cornell-smooth.xml -D res=256|$refs/cornell-smooth.exr|48|0 1|"
  "cornell-gold|$refs/cornell-gold.xml -D res=256|$refs/cornell-gold.exr|48|0 1|"
  "interior|scenes/interior.xml -D width=160 -D height=90 --photons-per-pass 200000|$refs/interior.exr|24|0 1|"
)
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  echo "| scene | build | seed | marks (emission, rough, lit) | pilot s | wall ms a pass | relMSE (region) |"
  echo "|---|---|---|---|---|---|---|"
  for entry in "${SCENES[@]}"; do
    IFS='|' read -r name scene ref passes seeds regions <<<"$entry"
    if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
    for seed in $seeds; do
      for build in BASE NEW; do
        bin=${!build}
        # shellcheck disable=SC2086
        log=$("$bin" render $scene --passes "$passes" --seed "$seed" --reference "$ref" $regions --profile \
          --out "/tmp/pilot-fresnel-$name-$build-$seed.exr" --force 2>&1 | grep -v '^warning')
        marks=$(grep -o 'emission [0-9.]*%, rough [0-9.]*%, lit [0-9.]*%' <<<"$log")
        pilot=$(grep -o 'pilot eye pass [0-9.]*' <<<"$log" | grep -o '[0-9.]*$')
        wall=$(grep -o 'wall [0-9.]*' <<<"$log" | head -1 | grep -o '[0-9.]*$')
        rel=$(grep -o 'relMSE [0-9.e-]*' <<<"$log" | grep -o '[0-9.e-]*$' | paste -sd' ')
        echo "| $name | $build | $seed | $marks | $pilot | $wall | $rel |"
      done
    done
  done
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$out"
