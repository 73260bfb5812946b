#!/usr/bin/env bash
# Whether the interior's disks cost as triangle lights (issue 39): the interior (9 disks: 2,304 emitting
# triangles), interior-squares.xml (the 9 as squares: quads) and interior-tri-squares.xml (the 9 squares as
# 18 emitting triangles), in one bench run and again in the reverse order; writes lights-as-triangles.txt.
set -euo pipefail
cd "$(dirname "$0")/../../.."
d=docs/measurements/issue39
{
  uptime
  target/release/ppm-vk bench --scene scenes/cornell-spheres.toml --scene scenes/interior.xml \
    --scene $d/interior-squares.xml --scene $d/interior-tri-squares.xml --cases 200k@320x180 --warmup 1 \
    --passes 3 --json $d/lights-as-triangles-1.json 2>&1 | grep -v '^  kernel'
  target/release/ppm-vk bench --scene scenes/cornell-spheres.toml --scene $d/interior-tri-squares.xml \
    --scene $d/interior-squares.xml --scene scenes/interior.xml --cases 200k@320x180 --warmup 1 \
    --passes 3 --json $d/lights-as-triangles-2.json 2>&1 | grep -v '^  kernel'
  uptime
} | tee $d/lights-as-triangles.txt
