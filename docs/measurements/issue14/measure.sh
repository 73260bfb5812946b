#!/usr/bin/env bash
# Issue 14 measurements: interleaved runs of the 98b7bf6 build and the new one, same machine, same session.
set -u
cd "$(dirname "$0")/../../.."
OLD_TREE=${OLD_TREE:-/path/to/98b7bf6-checkout}
OUT=${OUT:-/tmp/issue14}; mkdir -p $OUT
# OLD: ppm-vk built at 98b7bf6 (its own checkout, for its scene file); NEW: this build
OLD=${OLD:-/path/to/98b7bf6/target/release/ppm-vk}; NEW=${NEW:-target/release/ppm-vk}
REF=../shared/reference/cornell-spheres.exr
S=scenes/cornell-spheres.toml
date > $OUT/started
# A. bench, 1M photons at 512^2, SPPM + probe + cone (twice each, interleaved)
for round in 1 2; do
  $OLD bench --scene $OLD_TREE/scenes/cornell-spheres.toml --probe scale-free --cone 1.1 --cases 1M@512x512 --warmup 2 --passes 5 --json $OUT/bench-98b-$round.json > $OUT/bench-98b-$round.txt 2>&1
  $NEW bench --probe scale-free --cone 1.1 --cases 1M@512x512 --warmup 2 --passes 5 --breakdown --json $OUT/bench-new-$round.json > $OUT/bench-new-$round.txt 2>&1
done
# B. 60 s SPPM renders with probe and cone, error against the reference every 10 passes
for round in 1 2; do
  $OLD render $OLD_TREE/scenes/cornell-spheres.toml --time 60 --probe scale-free --cone 1.1 --reference $REF --error-every 10 -o $OUT/r60-98b-$round.exr --report $OUT/r60-98b-$round.json > $OUT/r60-98b-$round.txt 2>&1
  $NEW render $S --time 60 --probe scale-free --cone 1.1 --reference $REF --error-every 10 --force -o $OUT/r60-new-$round.exr --report $OUT/r60-new-$round.json > $OUT/r60-new-$round.txt 2>&1
done
# C. 300 passes each: gather ms per pass against the largest radius
$NEW render $S --passes 300 --probe scale-free --cone 1.1 --force -o $OUT/p300-new.exr --report $OUT/p300-new.json > $OUT/p300-new.txt 2>&1
$OLD render $OLD_TREE/scenes/cornell-spheres.toml --passes 300 --probe scale-free --cone 1.1 -o $OUT/p300-98b.exr --report $OUT/p300-98b.json > $OUT/p300-98b.txt 2>&1
# D. the 1M-triangle scene
$NEW bench --scene scenes/cornell-dense.toml --probe scale-free --cone 1.1 --cases 1M@512x512 --warmup 1 --passes 3 --breakdown --json $OUT/bench-dense-new.json > $OUT/bench-dense-new.txt 2>&1
$NEW bench --probe scale-free --cone 1.1 --cases 1M@512x512 --warmup 1 --passes 3 --breakdown --json $OUT/bench-cornell-new3.json > $OUT/bench-cornell-new3.txt 2>&1
# E. the equal-time table (10/30/60 s per variant)
V="ppm; ppm+probe-sf; sppm; sppm+probe-sf; sppm+cone; sppm+probe-sf+cone"
for t in 10 30 60; do
  $NEW compare $S --reference $REF --time $t --variants "$V" --out $OUT/equal-time-${t}s > $OUT/equal-time-${t}s.txt 2>&1
done
date > $OUT/done
