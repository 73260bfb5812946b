#!/bin/sh
# The cost of issue 36 on cornell-spheres: the build before it (497f1d9) and after, in interleaved rounds
# of one run on this machine (its speed drifts between hours): BASE and NEW are the two binaries.
set -e
OUT=docs/measurements/lights/bench
for round in 1 2 3; do
  for b in base new; do
    bin=$BASE; [ $b = new ] && bin=$NEW
    $bin bench --scene scenes/cornell-spheres.toml --cases 1M@512x512 --passes 5 --json $OUT/$b-$round.json \
      > $OUT/$b-$round.txt
  done
done
