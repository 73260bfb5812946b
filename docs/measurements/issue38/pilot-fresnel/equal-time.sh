#!/usr/bin/env bash
# Issue 38 at equal time after the pilot's Fresnel branches: glass-on-table at 256^2 given 60 s of passes
# (compare --time: set-up excluded) with three seeds, then Mitsuba 3's path tracer given the same 60 s three
# times right after, on the same machine (seed-to-seed spread is a third of the band's error in both).
# Writes equal-time.txt and the compare folders beside this.
# Usage: docs/measurements/issue38/pilot-fresnel/equal-time.sh [SECONDS]  (from the repository root; needs
# target/release/ppm-vk and `pip install mitsuba numpy` with libllvm19, ../shared/notes/TOOLCHAIN.md)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
PY=${PYTHON:-python3}
T=${1:-60}
o=docs/measurements/issue38/pilot-fresnel
refs=scenes/references
"$PY" -c "import sys; sys.path.insert(0, 'scenes/references'); import make_reference as m; \
m.split_obj('scenes/meshes/glass-on-table.obj', 'scenes/references/meshes')"
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  for seed in 0 1 2; do
    target/release/ppm-vk compare scenes/glass-on-table.toml --resolution 256x256 \
      --reference "$refs/glass-on-table.exr" --time "$T" --seed "$seed" --variants sppm \
      --region torus:80,110,96,40 --out "$o/glass-on-table-seed$seed" > "$o/glass-on-table-seed$seed.log" 2>&1
    echo "ppm-vk seed $seed:"
    grep '^|' "$o/glass-on-table-seed$seed/compare.md"
  done
  echo "== Mitsuba $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
  "$PY" docs/peers/mitsuba_equal_time.py "$refs/glass-on-table.xml" "$refs/glass-on-table.exr" --seconds "$T" \
    --runs 3 --res 256 --region torus=80,110,176,150
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} 2>&1 | tee "$o/equal-time.txt"
