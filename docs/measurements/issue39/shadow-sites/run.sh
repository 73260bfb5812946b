#!/usr/bin/env bash
# Issue 39: the eye pass with one traversal per shadow ray a vertex may send (ShadowRay in ray.comp) against
# the build before it (one traversal per kind of vertex that sends one). Two rounds, the order flipped in
# the second, each build one bench run over the mesh ladder and two scenes of rough vertices and coats;
# ratios are read within a run, the builds compared round by round. BEFORE_BIN: the build before (built from
# the parent commit); writes NAME-{before,after}-ROUND.{json,txt} beside this script.
# Usage: BEFORE_BIN=/tmp/ppm-vk-base docs/measurements/issue39/shadow-sites/run.sh [NAME]
set -euo pipefail
cd "$(dirname "$0")/../../../.."
docs/measurements/issue39/bench-rounds.sh docs/measurements/issue39/shadow-sites "${1:-bench}" \
  scenes/cornell-spheres.toml scenes/cornell-mesh.toml scenes/glass-on-table.toml scenes/cornell-dense.toml \
  scenes/interior.xml scenes/references/cornell-aniso.xml scenes/references/cornell-roughplastic.xml
