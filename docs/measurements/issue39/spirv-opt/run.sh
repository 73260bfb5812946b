#!/usr/bin/env bash
# Issue 39's set-up: what glslang's SPIR-V optimization (shaderc's OptimizationLevel, Performance in
# specialize.rs) costs and buys. Build with experiment.patch applied (an environment variable picks the
# level; not in the tree), then: the interior at 320x180, 200k photons, each level with fresh ppm-vk and
# Mesa caches (cold), then twice on them (warm; the second prints its passes' stage times too); the images of
# two passes compared with the first level's. Levels: the arguments (perf, size, zero), default perf zero.
# Usage: git apply docs/measurements/issue39/spirv-opt/experiment.patch && cargo build --release --bin ppm-vk
#        docs/measurements/issue39/spirv-opt/run.sh [LEVEL...]
#        git apply -R docs/measurements/issue39/spirv-opt/experiment.patch
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
if [ $# -gt 0 ]; then levels=("$@"); else levels=(perf zero); fi
for opt in "${levels[@]}"; do
  d=/tmp/optc-$opt
  rm -rf $d
  mkdir -p $d
  for run in cold warm warm2; do
    echo "== $opt $run"
    PPM_VK_EXPERIMENT_OPT=$opt MESA_SHADER_CACHE_DIR=$d/mesa target/release/ppm-vk render scenes/interior.xml \
      --passes 2 --photons-per-pass 200000 --profile --pipeline-cache $d/ppm -o /tmp/o-$opt.exr -f 2>&1 |
      grep -E "set-up|kernel (ray|photon) |^ +2 "
  done
done
for opt in "${levels[@]:1}"; do
  cmp "/tmp/o-${levels[0]}.exr" "/tmp/o-$opt.exr" && echo "$opt: the image is ${levels[0]}'s" || echo "$opt: the image differs from ${levels[0]}'s"
done
