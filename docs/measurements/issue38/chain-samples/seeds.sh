#!/usr/bin/env bash
# glass-on-table at equal passes (60), seeds 0-5: the build before chain pixels took every emission sample
# (BEFORE_BIN) and after (AFTER_BIN, default target/release/ppm-vk), the torus band and each render's
# wall time -> seeds.txt beside this.
# Usage: BEFORE_BIN=/path/to/ppm-vk docs/measurements/issue38/chain-samples/seeds.sh  (from the repository root)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
after=${AFTER_BIN:-target/release/ppm-vk}
out=docs/measurements/issue38/chain-samples/seeds.txt
echo "== start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg) build $(git rev-parse --short HEAD)" | tee "$out"
for seed in 0 1 2 3 4 5; do
  for b in before after; do
    bin=$BEFORE_BIN
    [ "$b" = after ] && bin=$after
    start=$(date +%s.%N)
    res=$("$bin" render scenes/glass-on-table.toml --resolution 256x256 --passes 60 --seed "$seed" \
      --reference scenes/references/glass-on-table.exr --region torus:80,110,96,40 --out /tmp/got.exr --force 2>&1 \
      | grep -A1 'error vs' | tr '\n' ' ')
    echo "$b seed $seed $(printf '%.1f' "$(echo "$(date +%s.%N) - $start" | bc)") s $res" | tee -a "$out"
  done
done
