#!/usr/bin/env bash
# Issue 38: cornell-aniso at 60 s, the default (16 eye paths where a rough lobe is seen) and
# --rough-samples 32, then Mitsuba 3's path tracer given the same 60 s right after, in one run.
# Usage: docs/measurements/issue38/rough-samples/mitsuba.sh [SECONDS]  (from the repository root; needs
# target/release/ppm-vk and `pip install mitsuba numpy` with libllvm19, ../shared/notes/TOOLCHAIN.md)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
PY=${PYTHON:-python3}
T=${1:-60}
o=docs/measurements/issue38/rough-samples
refs=scenes/references
echo "== cornell-aniso $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
target/release/ppm-vk compare $refs/cornell-aniso.xml -D res=256 --reference $refs/cornell-aniso.exr --time "$T" \
  --variants "sppm; sppm+rsp=32" --region gold:40,120,90,90 --region glass:100,140,90,90 \
  --out "$o/aniso-mitsuba" > "$o/aniso-mitsuba.log" 2>&1
grep '^|' "$o/aniso-mitsuba/compare.md"
"$PY" docs/peers/mitsuba_equal_time.py $refs/cornell-aniso.xml $refs/cornell-aniso.exr --seconds "$T" --runs 1 \
  --res 256 --region gold=40,120,130,210 --region glass=100,140,190,230 > "$o/aniso-mitsuba.txt" 2>&1
tail -n 3 "$o/aniso-mitsuba.txt"
echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
