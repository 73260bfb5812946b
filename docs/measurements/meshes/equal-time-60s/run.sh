#!/bin/bash
cd /work/main
for bin in before after; do
  /tmp/m/ppm-vk-$bin compare scenes/glass-on-table.toml --reference scenes/references/glass-on-table.exr --resolution 256x256 --time 60 --variants "sppm; sppm+probe-sf" --out /tmp/m/eq-got-$bin > /tmp/m/eq-got-$bin.log 2>&1
  /tmp/m/ppm-vk-$bin compare scenes/cornell-mesh.toml --reference ../shared/reference/cornell-spheres.exr --time 60 --variants "sppm; sppm+probe-sf" --out /tmp/m/eq-cm-$bin > /tmp/m/eq-cm-$bin.log 2>&1
done
DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 docs/peers/mitsuba_equal_time.py scenes/references/glass-on-table.xml scenes/references/glass-on-table.exr --seconds 10 30 60 > /tmp/m/mitsuba-got.csv 2> /tmp/m/mitsuba-got.err
echo done > /tmp/m/eqtime2.done
