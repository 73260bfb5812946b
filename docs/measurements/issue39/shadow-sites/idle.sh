#!/usr/bin/env bash
# What code that no lane runs costs on lavapipe: the tree's build against the same build with PATCH applied
# (idle-traversal.patch: two shadow-ray traversals in the emission samples' loop that no path reaches;
# idle-photon.patch: a second rough_bounce and plastic_scatter in the photon kernel that no photon reaches).
# The interior at 320x180, 200k photons, `render --profile`, two rounds A B A B; prints each pass's eye pass
# (ray) and photon stage in ms. Builds both binaries (copies in /tmp); leaves the tree as it found it.
# Usage: docs/measurements/issue39/shadow-sites/idle.sh PATCH > RECORD.txt
set -euo pipefail
cd "$(dirname "$0")/../../../.."
patch=$1
cargo build --release --bin ppm-vk > /dev/null 2>&1
cp target/release/ppm-vk /tmp/idle-tree
git apply "$patch"
trap 'git apply -R "$patch"' EXIT
cargo build --release --bin ppm-vk > /dev/null 2>&1
cp target/release/ppm-vk /tmp/idle-patched
echo "# $patch on $(git rev-parse --short HEAD), $(date -u +%H:%M) load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "build pass ray_ms photon_ms"
for round in 1 2; do
  for b in tree patched; do
    /tmp/idle-$b render scenes/interior.xml --photons-per-pass 200000 --profile --passes 3 \
      -o /tmp/idle.exr -f 2>&1 | awk -v b="$b" '$1 ~ /^[23]$/ && $2 ~ /^[0-9]+$/ {print b, $1, $3, $4}'
  done
done
