#!/usr/bin/env bash
# Issue 39: what the interior's photon stage spends on each kind of surface. The hall as it is and with one
# material at a time made diffuse (or the wood's texture a constant colour), generated from
# scenes/interior.xml by make.py beside this script; one bench run, 1M photons at 320x180, the photon
# kernel's breakdown (as rendered, without record stores, without the append, tracing alone) for each.
# Writes run.txt and run.json beside this script. The hall's meshes are generated, not in git: `cargo run
# --release -p ppm-vk-scene-gen --bin gen_scenes` first (scripts/test does).
set -euo pipefail
cd "$(dirname "$0")/../../../.."
o=docs/measurements/issue39/materials
python3 $o/make.py
args=()
for v in as-is wood-untextured wood-diffuse metal-diffuse glass-diffuse all-diffuse; do
  args+=(--scene "$o/interior-$v.xml")
done
target/release/ppm-vk bench "${args[@]}" --cases 1M@320x180 --warmup 1 --passes 3 --breakdown \
  --json $o/run.json 2>&1 | tee $o/run.txt
