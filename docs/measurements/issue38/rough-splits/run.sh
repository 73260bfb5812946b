#!/usr/bin/env bash
# Issue 38, the rough splits: every scene with a Mitsuba reference whose eye paths sample through rough
# lobes, 60 s of passes each for ppm-vk before the split (the build named by BEFORE, whose binary is
# BEFORE_BIN: one hit point a pixel, light samples as the pilot's other marks say), after it (the default:
# 4 lobe directions at the first rough vertex, those pixels taking every emission sample) and after it
# with one direction (rs=1: the more light samples alone), then Mitsuba 3's path tracer given the same 60 s
# on the same machine right after, scene by scene. The first ppm-vk build rotates from scene to scene.
# The scenes without rough vertices render as before, bit for bit (tests/bit-identical.json).
# Usage: BEFORE_BIN=/path/to/old/ppm-vk docs/measurements/issue38/rough-splits/run.sh [SECONDS] [scene ...]
# (from the repository root; target/release/ppm-vk; `pip install mitsuba numpy` with libllvm19,
# ../shared/notes/TOOLCHAIN.md; PYTHON= names the Python that has them, default python3). The recorded run
# built BEFORE_BIN from commit 349a0a8 in a worktree of its own (its shaders beside it).
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
PY=${PYTHON:-python3}
T=${1:-60}
shift || true
o=docs/measurements/issue38/rough-splits
refs=scenes/references
# name | scene and its flags | reference | compare regions (x,y,w,h) | Mitsuba regions (x0,y0,x1,y1)
SCENES=(
  "cornell-aniso|$refs/cornell-aniso.xml -D res=256|$refs/cornell-aniso.exr|gold:40,120,90,90 glass:100,140,90,90|gold=40,120,130,210 glass=100,140,190,230"
  "cornell-rough|$refs/cornell-rough.xml -D res=256|$refs/cornell-rough.exr||"
  "cornell-glossy|$refs/cornell-glossy.xml -D res=256|$refs/cornell-glossy.exr||"
  "cornell-glossy10|$refs/cornell-glossy10.xml -D res=256|$refs/cornell-glossy10.exr||"
)
i=0
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene ref cregions mregions <<<"$entry"
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  cr=(); for r in $cregions; do cr+=(--region "$r"); done
  mr=(); for r in $mregions; do mr+=(--region "$r"); done
  echo "== $name $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
  before() {
    # shellcheck disable=SC2086
    "$BEFORE_BIN" compare $scene --reference "$ref" --time "$T" --variants "sppm" "${cr[@]}" \
      --out "$o/$name-before" > "$o/$name-before.log" 2>&1
    grep '^| sppm' "$o/$name-before/compare.md" | sed 's/^| sppm /| before (349a0a8) /'
  }
  after() {
    # shellcheck disable=SC2086
    target/release/ppm-vk compare $scene --reference "$ref" --time "$T" --variants "sppm; sppm+rs=1" "${cr[@]}" \
      --out "$o/$name" > "$o/$name.log" 2>&1
    grep '^|' "$o/$name/compare.md"
  }
  if [ $((i % 2)) = 0 ]; then before; after; else after; before; fi
  i=$((i + 1))
  "$PY" docs/peers/mitsuba_equal_time.py "${ref%.exr}.xml" "$ref" --seconds "$T" --runs 1 --res 256 "${mr[@]}" \
    > "$o/$name-mitsuba.txt" 2>&1
  tail -n 3 "$o/$name-mitsuba.txt"
done
echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
