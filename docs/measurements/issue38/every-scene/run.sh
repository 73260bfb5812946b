#!/usr/bin/env bash
# Issue 38's closing table: every scene with a Mitsuba reference at 256^2 or more, ppm-vk's defaults
# (`sppm`) given SECONDS of passes (compare --time: set-up and the probe pass excluded), then Mitsuba 3's
# path tracer given the same SECONDS on the same machine right after, scene by scene (both renderers see
# the same hour). One seed each; OUT=DIR writes there instead of beside this script.
# Usage: docs/measurements/issue38/every-scene/run.sh [SECONDS] [scene ...]  (from the repository root;
# needs target/release/ppm-vk and `pip install mitsuba numpy` with libllvm19, ../shared/notes/TOOLCHAIN.md;
# PYTHON=path names the Python that has them, default python3). Summary: every-scene/table.py OUT.
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
PY=${PYTHON:-python3}
T=${1:-60}
shift || true
o=${OUT:-docs/measurements/issue38/every-scene}
mkdir -p "$o"
refs=scenes/references
# name | ppm-vk scene and its flags | reference | Mitsuba XML | Mitsuba --res | compare regions (x,y,w,h) | Mitsuba regions (x0,y0,x1,y1)
SCENES=(
  "glass-on-table|scenes/glass-on-table.toml --resolution 256x256|$refs/glass-on-table.exr|$refs/glass-on-table.xml|256|torus:80,110,96,40|torus=80,110,176,150"
  "cornell-spheres|scenes/cornell-spheres.toml|../shared/reference/cornell-spheres.exr|../shared/reference/cornell-spheres.xml|||caustic=250,436,320,476"
  "cornell-aniso|$refs/cornell-aniso.xml -D res=256|$refs/cornell-aniso.exr|$refs/cornell-aniso.xml|256|gold:40,120,90,90 glass:100,140,90,90|gold=40,120,130,210 glass=100,140,190,230"
  "cornell-rough|$refs/cornell-rough.xml -D res=256|$refs/cornell-rough.exr|$refs/cornell-rough.xml|256||"
  "cornell-glossy|$refs/cornell-glossy.xml -D res=256|$refs/cornell-glossy.exr|$refs/cornell-glossy.xml|256||"
  "cornell-roughplastic|$refs/cornell-roughplastic.xml -D res=256|$refs/cornell-roughplastic.exr|$refs/cornell-roughplastic.xml|256||"
  "cornell-smooth|$refs/cornell-smooth.xml -D res=256|$refs/cornell-smooth.exr|$refs/cornell-smooth.xml|256||"
  "cornell-coated|$refs/cornell-coated.xml -D res=256|$refs/cornell-coated.exr|$refs/cornell-coated.xml|256||"
  "cornell-gold|$refs/cornell-gold.xml -D res=256|$refs/cornell-gold.exr|$refs/cornell-gold.xml|256||"
  "cornell-textured|$refs/cornell-textured.xml -D res=256|$refs/cornell-textured.exr|$refs/cornell-textured.xml|256||"
  "cornell-box|scenes/cornell-box.toml --resolution 256x256|$refs/cornell-box.exr|$refs/cornell-box.xml|256||"
)
# Mitsuba's glass-on-table.xml reads the demo mesh split in two (make_reference.py's split_obj);
# `cargo run --release -p ppm-vk-scene-gen --bin gen_scenes` writes the demo mesh.
"$PY" -c "import sys; sys.path.insert(0, 'scenes/references'); import make_reference as m; \
m.split_obj('scenes/meshes/glass-on-table.obj', 'scenes/references/meshes')"
echo "build $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty)"
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene ref xml res cregions mregions <<<"$entry"
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  cr=(); for r in $cregions; do cr+=(--region "$r"); done
  mr=(); for r in $mregions; do mr+=(--region "$r"); done
  mres=(); [ -n "$res" ] && mres=(--res "$res")
  echo "== $name $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
  # shellcheck disable=SC2086
  target/release/ppm-vk compare $scene --reference "$ref" --time "$T" --variants sppm "${cr[@]}" \
    --out "$o/$name" > "$o/$name.log" 2>&1
  grep '^|' "$o/$name/compare.md"
  "$PY" docs/peers/mitsuba_equal_time.py "$xml" "$ref" --seconds "$T" --runs 1 "${mres[@]}" "${mr[@]}" \
    > "$o/$name-mitsuba.txt" 2>&1 || echo "Mitsuba failed on $name: $o/$name-mitsuba.txt"
  tail -n 3 "$o/$name-mitsuba.txt"
done
echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
