#!/usr/bin/env bash
# Issue 39, the pilot's emission mark only for emission met along a chain of mirrors and glass (not after a
# rough coat, whose light the shadow rays and the lobe already take by MIS): equal time, the build before
# (BEFORE_BIN) against this one, ROUNDS interleaved rounds (the order flipped each round), SECONDS of
# passes each, on the scenes with rough plastic coats and a reference: the interior at its reference's
# 160x90 and cornell-roughplastic at 256^2. Writes NAME-BUILD-ROUND.log and the compare tables to run.txt.
# Usage: BEFORE_BIN=/path/to/old/ppm-vk docs/measurements/issue39/marks/run.sh [SECONDS] [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
T=${1:-60}
R=${2:-2}
o=docs/measurements/issue39/marks
refs=scenes/references
SCENES=(
  "interior|scenes/interior.xml -D width=160 -D height=90|$refs/interior.exr"
  "cornell-roughplastic|$refs/cornell-roughplastic.xml -D res=256|$refs/cornell-roughplastic.exr"
)
run() { # build-name binary scene-entry round
  IFS='|' read -r name scene ref <<<"$3"
  # shellcheck disable=SC2086
  "$2" compare $scene --reference "$ref" --time "$T" --variants sppm --out "/tmp/marks-$name-$1-$4" \
    > "$o/$name-$1-$4.log" 2>&1
  grep '^| sppm' "/tmp/marks-$name-$1-$4/compare.md" | sed "s/^| sppm /| $name $1 (round $4) /"
}
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "| scene build (round) | set-up s | passes | RMSE | relMSE |"
  for r in $(seq 1 "$R"); do
    for entry in "${SCENES[@]}"; do
      if [ $((r % 2)) = 1 ]; then run before "$BEFORE_BIN" "$entry" "$r"; run after target/release/ppm-vk "$entry" "$r"
      else run after target/release/ppm-vk "$entry" "$r"; run before "$BEFORE_BIN" "$entry" "$r"; fi
    done
  done
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$o/run.txt"
