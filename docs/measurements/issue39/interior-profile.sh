#!/usr/bin/env bash
# The interior's set-up (cold: empty ppm-vk and Mesa caches; then warm: the same caches again) and where its
# eye pass goes (the same render with one kind of eye-pass work reduced at a time), issue 39, before any
# change. 320x180 (the issue's size), 200k photons a pass; writes NAME.txt beside this script (NAME: the
# first argument, default interior-profile).
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/measurements/issue39/${1:-interior-profile}.txt
bin=target/release/ppm-vk
cache=$(mktemp -d)
mesa=$(mktemp -d)
export MESA_SHADER_CACHE_DIR=$mesa
run() { echo "== $*"; "$bin" render scenes/interior.xml --photons-per-pass 200000 --pipeline-cache "$cache" --profile --out /tmp/interior-profile.exr --force "$@" 2>&1 | grep -v '^warning'; }
{
  uptime
  run --passes 1 # cold
  run --passes 1 # warm
  # The eye pass (the `ray` column) by what it does, two rounds interleaved (this machine's load drifts;
  # the first round also compiles each variant's kernels); read it against the photon column of the same
  # run, which the variants leave alone.
  for round in 1 2; do
    for v in "" "--emission-samples 0" "--light-samples 1" "--direct photons" "--glossy-light bsdf" "--hit-slots 1"; do
      run --passes 3 $v
    done
  done
  uptime
} | tee "$out"
rm -rf "$cache" "$mesa"
