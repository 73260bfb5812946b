#!/usr/bin/env bash
# What the interior's disk lights cost as fans of 256 emitting triangles (2,304 light-table entries and BVH
# triangles): the interior against interior-squares.xml (the same lights as squares of equal area, 13
# light-table entries), interleaved A B A B in one bench run; writes disks-vs-squares.{json,txt}.
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/measurements/issue39
sq=$out/interior-squares.xml
# Two runs, A B A B then B A B A, so that a drift of the machine's load favours neither.
target/release/ppm-vk bench --scene scenes/cornell-spheres.toml --scene scenes/interior.xml --scene $sq \
  --scene scenes/interior.xml --scene $sq --cases 200k@320x180 --warmup 1 --passes 3 \
  --json $out/disks-vs-squares.json 2>&1 | grep -v '^  kernel' | tee $out/disks-vs-squares.txt
target/release/ppm-vk bench --scene scenes/cornell-spheres.toml --scene $sq --scene scenes/interior.xml \
  --scene $sq --scene scenes/interior.xml --cases 200k@320x180 --warmup 1 --passes 3 \
  --json $out/disks-vs-squares-2.json 2>&1 | grep -v '^  kernel' | tee $out/disks-vs-squares-2.txt
