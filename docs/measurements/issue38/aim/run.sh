#!/usr/bin/env bash
# Issue 38, photons aimed at what casts caustics at equal time: the default (no photon aimed) against
# --caustic-photons 0.25 and 0.5 (compare's aim=S), SECONDS of passes each, the variants' order rotated
# scene by scene; then, where the entry names its XML, Mitsuba 3's path tracer given the same seconds on
# the same machine right after. Writes NAME/ (compare's table, JSON, plot, PNGs), NAME.log and
# NAME-mitsuba.txt beside this script, and the table rows to run.txt.
# Usage: docs/measurements/issue38/aim/run.sh [SECONDS] [scene ...]  (from the repository root; needs
# target/release/ppm-vk, and for Mitsuba `pip install mitsuba numpy` with libllvm19 as in
# ../shared/notes/TOOLCHAIN.md; PYTHON names the Python that has them, default python3)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
PY=${PYTHON:-python3}
T=${1:-60}
shift || true
o=docs/measurements/issue38/aim
refs=scenes/references
# name | ppm-vk scene and its flags | reference | Mitsuba XML (empty: ppm-vk only) | Mitsuba --res | compare regions | Mitsuba regions
SCENES=(
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|$refs/glass-on-table.exr|$refs/glass-on-table.xml|256|torus:80,110,96,40|torus=80,110,176,150"
  "cornell-spheres|scenes/cornell-spheres.toml|../shared/reference/cornell-spheres.exr||||"
  "cornell-aniso|$refs/cornell-aniso.xml -D res=256|$refs/cornell-aniso.exr||256|gold:40,120,90,90 glass:100,140,90,90|"
)
VARIANTS=("sppm" "sppm+aim=0.25" "sppm+aim=0.5")
"$PY" -c "import sys; sys.path.insert(0, 'scenes/references'); import make_reference as m; \
m.split_obj('scenes/meshes/glass-on-table.obj', 'scenes/references/meshes')"
i=0
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  for entry in "${SCENES[@]}"; do
    IFS='|' read -r name scene ref xml res cregions mregions <<<"$entry"
    if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
    n=${#VARIANTS[@]}
    v=""; for k in $(seq 0 $((n - 1))); do v+="${VARIANTS[$(((k + i) % n))]}; "; done
    i=$((i + 1))
    cr=(); for r in $cregions; do cr+=(--region "$r"); done
    mr=(); for r in $mregions; do mr+=(--region "$r"); done
    mres=(); [ -n "$res" ] && mres=(--res "$res")
    echo "== $name $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg): $v"
    # shellcheck disable=SC2086
    target/release/ppm-vk compare $scene --reference "$ref" --time "$T" --variants "$v" "${cr[@]}" \
      --out "$o/$name" > "$o/$name.log" 2>&1
    grep '^|' "$o/$name/compare.md"
    if [ -n "$xml" ]; then
      "$PY" docs/peers/mitsuba_equal_time.py "$xml" "$ref" --seconds "$T" --runs 1 "${mres[@]}" "${mr[@]}" \
        > "$o/$name-mitsuba.txt" 2>&1 || echo "Mitsuba failed on $name: $o/$name-mitsuba.txt"
      tail -n 3 "$o/$name-mitsuba.txt"
    fi
  done
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$o/run.txt"
