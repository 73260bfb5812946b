#!/usr/bin/env bash
# The grid build's scan by subgroup arithmetic against the Hillis-Steele scan in shared memory: one
# `render --profile` of cornell-spheres (512^2, 8 passes) with each build, before first; prints passes 4-8
# (the scan is the `lookup/scan` column, with the partition offsets).
# Usage: BEFORE_BIN=<ppm-vk of build 646b349> AFTER_BIN=target/release/ppm-vk docs/measurements/issue39/grid-scan/run.sh
set -euo pipefail
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
out=$(mktemp -d)
for which in BEFORE AFTER; do
  bin=${which}_BIN
  echo "== $which"
  "${!bin}" render scenes/cornell-spheres.toml --passes 8 --profile --force --out "$out/$which.exr" 2>&1 \
    | awk '/pass +records/{p=1} p && ($1 == "pass" || $1 >= 4)'
done
cmp -s "$out/BEFORE.exr" "$out/AFTER.exr" && echo "the images are the same, bit for bit" || echo "the images differ"
rm -rf "$out"
