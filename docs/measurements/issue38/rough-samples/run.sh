#!/usr/bin/env bash
# Issue 38, eye paths where a rough lobe is seen (`--rough-samples`): each scene whose eye paths sample
# through rough metal or rough glass, 60 s of passes per variant (compare --time), the variants in one run
# so they see the same hour: rsp=16 (every marked pixel emission_samples: the rule before, and the default
# after this run), 32 and 64. run.txt's `sppm` rows are rsp=32, the default of the build that ran it
# (fa29023 plus the change with 32 as its default, before the default went back to 16 in c1b1efb).
# Usage: docs/measurements/issue38/rough-samples/run.sh [SECONDS] [scene ...]  (from the repository root;
# needs target/release/ppm-vk)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
T=${1:-60}
shift || true
o=docs/measurements/issue38/rough-samples
refs=scenes/references
# name | ppm-vk scene and its flags | compare regions (x,y,w,h)
SCENES=(
  "cornell-aniso|$refs/cornell-aniso.xml -D res=256|gold:40,120,90,90 glass:100,140,90,90"
  "cornell-rough|$refs/cornell-rough.xml -D res=256|"
  "cornell-glossy|$refs/cornell-glossy.xml -D res=256|"
  "cornell-glossy10|$refs/cornell-glossy10.xml -D res=256|"
)
for entry in "${SCENES[@]}"; do
  IFS='|' read -r name scene cregions <<<"$entry"
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  cr=(); for r in $cregions; do cr+=(--region "$r"); done
  echo "== $name $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
  # shellcheck disable=SC2086
  target/release/ppm-vk compare $scene --reference "$refs/$name.exr" --time "$T" \
    --variants "sppm+rsp=16; sppm+rsp=32; sppm+rsp=64" "${cr[@]}" --out "$o/$name" > "$o/$name.log" 2>&1
  grep '^|' "$o/$name/compare.md"
done
echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
