#!/usr/bin/env bash
# Issue 39: the interior's set-up at 320x180 (200k photons), the pilot at 16 samples in every pixel (the
# rule before) against the default (4 in every pixel, 16 where those met a mirror or glass); one
# pipeline and Mesa cache, warmed by the first run of each, then ROUNDS interleaved rounds. Writes setup.txt.
# Usage: docs/measurements/issue39/pilot/setup.sh [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
R=${1:-3}
bin=${BIN:-target/release/ppm-vk}
cache=$(mktemp -d)
export MESA_SHADER_CACHE_DIR=$(mktemp -d)
run() {
  "$bin" render scenes/interior.xml --photons-per-pass 200000 --passes 1 --pipeline-cache "$cache" --profile \
    --pilot-samples "$1" --out /tmp/pilot-setup.exr --force 2>&1 | grep '^set-up' | sed "s/^/pilot-samples $1: /"
}
{
  echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)"
  echo "-- warm-up (compiles)"
  run 16
  run 4
  echo "-- warm"
  for r in $(seq 1 "$R"); do
    if [ $((r % 2)) = 1 ]; then run 16; run 4; else run 4; run 16; fi
  done
  echo "== done $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee docs/measurements/issue39/pilot/setup.txt
rm -rf "$cache" "$MESA_SHADER_CACHE_DIR"
