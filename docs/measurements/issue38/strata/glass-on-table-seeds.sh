#!/usr/bin/env bash
# glass-on-table at equal passes (60), seeds 0-5, the build before stratified positions (BEFORE_BIN) and
# after (AFTER_BIN, default target/release/ppm-vk), with its torus band -> glass-on-table-seeds.txt
# ("cur" is the build before, "strata" the build after).
set -euo pipefail
cd "$(dirname "$0")/../../../.."
after=${AFTER_BIN:-target/release/ppm-vk}
for seed in 0 1 2 3 4 5; do
  for b in cur strata; do
    bin=$BEFORE_BIN
    [ "$b" = strata ] && bin=$after
    echo "$b seed $seed $("$bin" render scenes/glass-on-table.toml --resolution 256x256 --passes 60 --seed "$seed" \
      --reference scenes/references/glass-on-table.exr --region torus:80,110,96,40 --out /tmp/got.exr --force 2>&1 \
      | grep -A1 'error vs' | tr '\n' ' ')"
  done
done
