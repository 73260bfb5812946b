#!/bin/bash
cd "$(dirname "$0")/../../../.."  # the repository
# ppm-vk: the release binary of the build measured (git_revision in each report)
out=${OUT:-equal-passes}; mkdir -p $out
for v in ${VARIANTS:-off nearest scale-free curvature}; do
  ppm-vk render scenes/glass-on-table.toml --resolution 256x256 --probe $v --passes 20 --reference scenes/references/glass-on-table.exr --error-every 20 -o $out/got-$v.exr -f > $out/got-$v.txt 2>&1
done
for v in ${VARIANTS:-off nearest scale-free curvature}; do
  ppm-vk render scenes/cornell-spheres.toml --probe $v --passes 16 --reference ../shared/reference/cornell-spheres.exr --error-every 16 -o $out/cs-$v.exr -f > $out/cs-$v.txt 2>&1
done
for v in ${VARIANTS:-off nearest scale-free curvature}; do
  ppm-vk render scenes/cornell-box.toml --probe $v --passes 16 --reference scenes/references/cornell-box.exr --error-every 16 -o $out/cb-$v.exr -f > $out/cb-$v.txt 2>&1
done
echo done > $out/done
