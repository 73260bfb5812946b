#!/usr/bin/env bash
# Issue 14, third session: interleaved runs of the 98b7bf6 build (the build the issue names) and this
# one, same machine, same session. OLD: ppm-vk built at 98b7bf6; OLD_SCENE: that commit's
# scenes/cornell-spheres.toml (`git show 98b7bf6:scenes/cornell-spheres.toml`); NEW: this build.
set -u
cd "$(dirname "$0")/../../.."
OLD=${OLD:-/path/to/98b7bf6/target/release/ppm-vk}; OLD_SCENE=${OLD_SCENE:-/path/to/98b7bf6-cornell-spheres.toml}
NEW=${NEW:-target/release/ppm-vk}
OUT=${OUT:-/tmp/issue14-c}; mkdir -p $OUT
REF=../shared/reference/cornell-spheres.exr
S=scenes/cornell-spheres.toml
date > $OUT/started
# A. 60 s SPPM renders with the probe and the cone filter, error against the reference every 10 passes
for round in ${ROUNDS:-1 2 3}; do
  $OLD render $OLD_SCENE --time 60 --probe scale-free --cone 1.1 --reference $REF --error-every 10 -o $OUT/r60-98b-$round.exr --report $OUT/r60-98b-$round.json > $OUT/r60-98b-$round.txt 2>&1
  $NEW render $S --time 60 --probe scale-free --cone 1.1 --reference $REF --error-every 10 --force -o $OUT/r60-new-$round.exr --report $OUT/r60-new-$round.json > $OUT/r60-new-$round.txt 2>&1
done
# B. bench, 1M photons at 512^2, SPPM + probe + cone
for round in ${BENCH_ROUNDS:-1 2}; do
  $OLD bench --scene $OLD_SCENE --probe scale-free --cone 1.1 --cases 1M@512x512 --warmup 2 --passes 5 --json $OUT/bench-98b-$round.json > $OUT/bench-98b-$round.txt 2>&1
  $NEW bench --probe scale-free --cone 1.1 --cases 1M@512x512 --warmup 2 --passes 5 --breakdown --json $OUT/bench-new-$round.json > $OUT/bench-new-$round.txt 2>&1
done
date > $OUT/done
# C. 300 passes of this build: gather ms per pass against the largest radius (98b7bf6: ../issue14/p300-98b.json)
$NEW render $S --passes 300 --probe scale-free --cone 1.1 --force -o $OUT/p300-new.exr --report $OUT/p300-new.json > $OUT/p300-new.txt 2>&1
# D. the equal-time table (10/30/60 s per variant)
V="ppm; ppm+probe-sf; sppm; sppm+probe-sf; sppm+cone; sppm+probe-sf+cone"
for t in 10 30 60; do
  $NEW compare $S --reference $REF --time $t --variants "$V" --out $OUT/equal-time-${t}s > $OUT/equal-time-${t}s.txt 2>&1
done
date > $OUT/done-all
