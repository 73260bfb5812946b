#!/usr/bin/env bash
# Issue 39's set-up: what glslang's SPIR-V optimization (shaderc's OptimizationLevel, Performance in
# specialize.rs) costs and buys. Build with experiment.patch applied (an environment variable picks the
# level; not in the tree), then: the interior at 320x180, 200k photons, each level with fresh ppm-vk and
# Mesa caches (cold), then twice on them (warm); the images of two passes compared.
# Usage: git apply docs/measurements/issue39/spirv-opt/experiment.patch && cargo build --release --bin ppm-vk
#        docs/measurements/issue39/spirv-opt/run.sh; git apply -R docs/measurements/issue39/spirv-opt/experiment.patch
set -euo pipefail
cd "$(dirname "$0")/../../../.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
for opt in perf zero; do
  d=/tmp/optc-$opt
  rm -rf $d
  mkdir -p $d
  for run in cold warm warm2; do
    echo "== $opt $run"
    PPM_VK_EXPERIMENT_OPT=$opt MESA_SHADER_CACHE_DIR=$d/mesa target/release/ppm-vk render scenes/interior.xml \
      --passes 2 --photons-per-pass 200000 --profile --pipeline-cache $d/ppm -o /tmp/o-$opt.exr -f 2>&1 |
      grep -E "set-up|kernel (ray|photon) "
  done
done
cmp /tmp/o-perf.exr /tmp/o-zero.exr && echo "the images are the same" || echo "the images differ"
