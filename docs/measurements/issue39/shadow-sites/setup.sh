#!/usr/bin/env bash
# Issue 39: the interior's set-up at 320x180 (200k photons) with one traversal per shadow ray a vertex may
# send against the build before (BEFORE_BIN), cold (empty ppm-vk and Mesa caches) then warm (the same
# caches again), two rounds in opposite orders. Prints each render's set-up and ray-kernel lines.
# Usage: BEFORE_BIN=/tmp/ppm-vk-base docs/measurements/issue39/shadow-sites/setup.sh > .../setup.txt
set -euo pipefail
cd "$(dirname "$0")/../../../.."
run() {
  local cache mesa
  cache=$(mktemp -d)
  mesa=$(mktemp -d)
  for state in cold warm; do
    echo "$2 $state: $(MESA_SHADER_CACHE_DIR=$mesa "$1" render scenes/interior.xml --photons-per-pass 200000 \
      --passes 1 --profile --pipeline-cache "$cache" -o /tmp/shadow-sites-setup.exr -f 2>&1 \
      | grep -E '^set-up|kernel ray' | tr -s ' ' | tr '\n' ' ')"
  done
  rm -rf "$cache" "$mesa"
}
uptime
for round in 1 2; do
  if [ "$round" = 1 ]; then order="before after"; else order="after before"; fi
  for b in $order; do
    if [ "$b" = before ]; then run "$BEFORE_BIN" "before, round $round"; else run target/release/ppm-vk "after, round $round"; fi
  done
done
uptime
