#!/usr/bin/env bash
# Issue 38 at equal time after the pilot's Fresnel branches: a scene given 60 s of passes (compare --time:
# set-up excluded) with three seeds of ppm-vk (the default), then Mitsuba 3's path tracer given the same 60 s
# a few times right after, on the same machine (seed-to-seed spread is a third of the error in both).
# glass-on-table: its torus band, three Mitsuba runs; cornell-aniso: its gold and glass spheres (how much of
# the gold's 1.30x in history-60s, one seed, is the seed), two Mitsuba runs. Writes equal-time-SCENE.txt
# and the compare folders SCENE-seedN beside this (or in $OUT, for a later build's record).
# Usage: [OUT=DIR] docs/measurements/issue38/pilot-fresnel/equal-time.sh SCENE [SECONDS]  (from the repository root;
# needs target/release/ppm-vk and `pip install mitsuba numpy` with libllvm19, ../shared/notes/TOOLCHAIN.md)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
PY=${PYTHON:-python3}
name=$1
T=${2:-60}
o=${OUT:-docs/measurements/issue38/pilot-fresnel}
mkdir -p "$o"
refs=scenes/references
case $name in
  glass-on-table)
    scene=(scenes/glass-on-table.toml --resolution 256x256)
    cregions=(--region torus:80,110,96,40)
    mregions=(--region torus=80,110,176,150)
    runs=3
    # Mitsuba's glass-on-table.xml reads the demo mesh split in two (make_reference.py's split_obj).
    "$PY" -c "import sys; sys.path.insert(0, 'scenes/references'); import make_reference as m; \
m.split_obj('scenes/meshes/glass-on-table.obj', 'scenes/references/meshes')" ;;
  cornell-aniso)
    scene=("$refs/cornell-aniso.xml" -D res=256)
    cregions=(--region gold:40,120,90,90 --region glass:100,140,90,90)
    mregions=(--region gold=40,120,130,210 --region glass=100,140,190,230)
    runs=2 ;;
  *) echo "equal-time.sh: unknown scene $name (glass-on-table, cornell-aniso)" >&2; exit 2 ;;
esac
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  for seed in 0 1 2; do
    target/release/ppm-vk compare "${scene[@]}" --reference "$refs/$name.exr" --time "$T" --seed "$seed" \
      --variants sppm "${cregions[@]}" --out "$o/$name-seed$seed" > "$o/$name-seed$seed.log" 2>&1
    echo "ppm-vk seed $seed:"
    grep '^|' "$o/$name-seed$seed/compare.md"
  done
  echo "== Mitsuba $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
  "$PY" docs/peers/mitsuba_equal_time.py "$refs/$name.xml" "$refs/$name.exr" --seconds "$T" --runs "$runs" \
    --res 256 "${mregions[@]}"
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} 2>&1 | tee "$o/equal-time-$name.txt"
