#!/usr/bin/env bash
# Issue 38: how much of glass-on-table's error at equal time is bias (the radius blurring the caustic) and
# how much noise. Each variant renders twice for SECONDS (default 60) with two seeds; decompose.py splits
# the error: the two runs' difference is noise alone (var = mean((x1 - x2)^2) / 2), their mean's error is
# bias^2 + var / 2. 256^2, the torus region of docs/accuracy.md. Writes run.txt beside this script.
# Usage: docs/measurements/issue38/bias-noise/run.sh [SECONDS] (from the repository root; numpy and the
# mitsuba pip package read the EXR files, DRJIT_LIBLLVM_PATH as ../shared/notes/TOOLCHAIN.md says).
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
T=${1:-60}
o=docs/measurements/issue38/bias-noise
ref=scenes/references/glass-on-table.exr
VARIANTS=(
  "default|"
  "alpha-0.5|--alpha 0.5"
  "nearest-16|--probe nearest --probe-k 16"
)
{
  echo "== $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg), ${T} s a run"
  for entry in "${VARIANTS[@]}"; do
    IFS='|' read -r name flags <<<"$entry"
    for seed in 1 2; do
      # shellcheck disable=SC2086
      target/release/ppm-vk render scenes/glass-on-table.toml --resolution 256x256 --time "$T" --seed $seed $flags \
        --reference "$ref" --region torus:80,110,96,40 --out "/tmp/bias-noise-$name-$seed.exr" --force 2>&1 |
        grep -E "passes,|relMSE" | sed "s/^/$name seed $seed: /"
    done
    python3 $o/decompose.py "$name" "/tmp/bias-noise-$name-1.exr" "/tmp/bias-noise-$name-2.exr" "$ref"
  done
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee $o/run.txt
# Then the same alpha against the default on two other scenes, 60 s each, one seed (-> alpha.txt):
#   target/release/ppm-vk compare scenes/cornell-spheres.toml --reference ../shared/reference/cornell-spheres.exr \
#     --time 60 --variants "sppm; sppm+alpha=0.5" --out /tmp/alpha-cs
#   target/release/ppm-vk compare scenes/references/cornell-aniso.xml -D res=256 \
#     --reference scenes/references/cornell-aniso.exr --time 60 --variants "sppm; sppm+alpha=0.5" --out /tmp/alpha-ca
