#!/usr/bin/env bash
# Issue 39: kernels specialised to the microfacet distributions a scene uses (SCENE_GGX, SCENE_BECKMANN in
# microfacet.glsl) against the build before (BEFORE_BIN, both distributions' code in every kernel). Two
# bench rounds, the order flipped in the second, over cornell-spheres (no rough surface: unchanged) and the
# interior (GGX only); then the interior's set-up, cold and warm (../shadow-sites/setup.sh). Writes
# bench-{before,after}-ROUND.{json,txt} and setup.txt beside this script.
# Usage: BEFORE_BIN=/tmp/ppm-vk-base docs/measurements/issue39/microfacet-kinds/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."
o=docs/measurements/issue39/microfacet-kinds
docs/measurements/issue39/bench-rounds.sh $o bench scenes/cornell-spheres.toml scenes/interior.xml
docs/measurements/issue39/shadow-sites/setup.sh | tee "$o/setup.txt"
