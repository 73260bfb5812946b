#!/usr/bin/env bash
# Issue 38: glass-on-table at 60 s of passes, the default (curvature probe, one pass's 1M probe photons)
# against the same with 4M probe photons, then Mitsuba 3's path tracer the same 60 s right after.
# Usage: docs/measurements/issue38/probe-photons/equal-time.sh [SECONDS]  (PYTHON= a Python with mitsuba)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
PY=${PYTHON:-python3}
T=${1:-60}
o=docs/measurements/issue38/probe-photons
refs=scenes/references
echo "== $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
target/release/ppm-vk compare scenes/glass-on-table.toml --resolution 256x256 --reference $refs/glass-on-table.exr \
  --time "$T" --variants "sppm; sppm+pp=4000000" --region torus:80,110,96,40 --out "$o/glass-on-table-60s" \
  > "$o/glass-on-table-60s.log" 2>&1
grep '^|' "$o/glass-on-table-60s/compare.md"
"$PY" docs/peers/mitsuba_equal_time.py $refs/glass-on-table.xml $refs/glass-on-table.exr --seconds "$T" --runs 1 \
  --res 256 --region torus=80,110,176,150 > "$o/glass-on-table-60s-mitsuba.txt" 2>&1
tail -n 3 "$o/glass-on-table-60s-mitsuba.txt"
echo "== $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
