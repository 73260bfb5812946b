#!/usr/bin/env bash
# Wall time of one worker's 32 probabilistic passes against 32 ordinary SPPM passes (`--method independent`
# with one worker: the ordinary render through the same code path, set-up included in both), interleaved,
# three times each, at two resolutions. Usage: overhead.sh OUTDIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../../.." && pwd)
bin=${PPM_VK:-$root/target/release/ppm-vk}
out=$1
mkdir -p "$out"
for res in 128x128 256x256; do
  for rep in 1 2 3; do
    for method in probabilistic independent; do
      line=$("$bin" render "$root/scenes/cornell-spheres.toml" --resolution $res --photons-per-pass 50000 \
        --passes 32 --worker 0 --of 1 --method $method -o "$out/o.part" --force 2>/dev/null)
      echo "$res $rep $method ${line##* in }"
    done
  done
done
