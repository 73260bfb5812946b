#!/bin/bash
# The first session's final build (31140b6) against this one, 60 s renders, interleaved.
cd "$(dirname "$0")/../../.."; mkdir -p ${OUT:-/tmp/ab}
REF=../shared/reference/cornell-spheres.exr
for round in 1 2; do
  ${PREV:-/path/to/31140b6/target/release/ppm-vk} render scenes/cornell-spheres.toml --time 60 --probe scale-free --cone 1.1 --reference $REF --error-every 10 --force -o ${OUT:-/tmp/ab}/r60-311-$round.exr --report ${OUT:-/tmp/ab}/r60-311-$round.json > ${OUT:-/tmp/ab}/r60-311-$round.txt 2>&1
  target/release/ppm-vk render scenes/cornell-spheres.toml --time 60 --probe scale-free --cone 1.1 --reference $REF --error-every 10 --force -o ${OUT:-/tmp/ab}/r60-new-$round.exr --report ${OUT:-/tmp/ab}/r60-new-$round.json > ${OUT:-/tmp/ab}/r60-new-$round.txt 2>&1
done

