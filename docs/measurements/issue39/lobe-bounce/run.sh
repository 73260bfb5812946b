#!/usr/bin/env bash
# Issue 39: the photon kernel's plastics, rough conductors and rough glass sampled in one routine
# (photon/lobe_bounce.glsl) against the build before (BEFORE_BIN: a sampler per surface). Two bench rounds,
# the order flipped in the second, over cornell-spheres (no such surface), the interior (rough plastic and
# rough metal), cornell-roughplastic, cornell-aniso (rough metal and glass) and cornell-coated (smooth
# plastic). Writes bench-{before,after}-ROUND.{json,txt} beside this script.
# Usage: BEFORE_BIN=/tmp/ppm-vk-base docs/measurements/issue39/lobe-bounce/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."
docs/measurements/issue39/bench-rounds.sh docs/measurements/issue39/lobe-bounce bench scenes/cornell-spheres.toml \
  scenes/interior.xml scenes/references/cornell-roughplastic.xml scenes/references/cornell-aniso.xml \
  scenes/references/cornell-coated.xml
