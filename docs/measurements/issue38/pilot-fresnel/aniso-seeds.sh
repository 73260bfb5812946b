#!/usr/bin/env bash
# Issue 38: cornell-aniso's gold and glass spheres at 60 s with three seeds of ppm-vk (the default), then
# Mitsuba 3's path tracer given the same 60 s twice, on the same machine: how much of the gold's 1.30x
# (history-60s, one seed) is the seed. Writes aniso-seeds.txt and the compare folders beside this.
# Usage: docs/measurements/issue38/pilot-fresnel/aniso-seeds.sh [SECONDS]  (from the repository root; needs
# target/release/ppm-vk and `pip install mitsuba numpy` with libllvm19, ../shared/notes/TOOLCHAIN.md)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
PY=${PYTHON:-python3}
T=${1:-60}
o=docs/measurements/issue38/pilot-fresnel
refs=scenes/references
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  for seed in 0 1 2; do
    target/release/ppm-vk compare "$refs/cornell-aniso.xml" -D res=256 --reference "$refs/cornell-aniso.exr" \
      --time "$T" --seed "$seed" --variants sppm --region gold:40,120,90,90 --region glass:100,140,90,90 \
      --out "$o/cornell-aniso-seed$seed" > "$o/cornell-aniso-seed$seed.log" 2>&1
    echo "ppm-vk seed $seed:"
    grep '^|' "$o/cornell-aniso-seed$seed/compare.md"
  done
  echo "== Mitsuba $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
  "$PY" docs/peers/mitsuba_equal_time.py "$refs/cornell-aniso.xml" "$refs/cornell-aniso.exr" --seconds "$T" \
    --runs 2 --res 256 --region gold=40,120,130,210 --region glass=100,140,190,230
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} 2>&1 | tee "$o/aniso-seeds.txt"
