#!/usr/bin/env bash
# After the disk lights became analytic disks (one light, one quad each, no fan in the BVH): the interior
# against interior-squares.xml (the same lights as squares of equal area) in both orders in one bench
# run, as disks-vs-squares.sh measured the fans; writes disks-analytic.{json,txt}.
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/measurements/issue39
sq=$out/interior-squares.xml
target/release/ppm-vk bench --scene scenes/cornell-spheres.toml --scene scenes/interior.xml --scene $sq \
  --scene $sq --scene scenes/interior.xml --cases 200k@320x180 --warmup 1 --passes 3 \
  --json $out/disks-analytic.json 2>&1 | grep -v '^  kernel' | tee $out/disks-analytic.txt
