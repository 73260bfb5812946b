#!/usr/bin/env bash
# Bias and variance of the error across seeds (bias_variance.py): glass-on-table's torus band from run.sh's
# seven seeds of each build (its images in /tmp, so run run.sh first), and cornell-aniso's spheres at 31
# passes (about 60 s) with three seeds of this build. Writes bias-variance.txt beside this.
# Usage: docs/measurements/issue38/pilot-fresnel/bias-variance.sh  (from the repository root)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
o=docs/measurements/issue38/pilot-fresnel
refs=scenes/references
{
  for build in BASE NEW; do
    echo "== glass-on-table, $build, 140 passes, seeds 0-6"
    python3 $o/bias_variance.py $refs/glass-on-table.exr $refs/glass-on-table_var.exr \
      "{'image': (0, 0, 256, 256), 'torus': (80, 110, 176, 150)}" /tmp/pilot-fresnel-glass-on-table-$build-{0..6}.exr
  done
  for seed in 0 1 2; do
    target/release/ppm-vk render $refs/cornell-aniso.xml -D res=256 --passes 31 --seed $seed \
      --out /tmp/bias-variance-aniso-$seed.exr --force > /dev/null 2>&1
  done
  echo "== cornell-aniso, $(git rev-parse --short HEAD), 31 passes, seeds 0-2"
  python3 $o/bias_variance.py $refs/cornell-aniso.exr $refs/cornell-aniso_var.exr \
    "{'image': (0, 0, 256, 256), 'gold': (40, 120, 130, 210), 'glass': (100, 140, 190, 230)}" \
    /tmp/bias-variance-aniso-{0..2}.exr
} | tee $o/bias-variance.txt
