#!/bin/bash
# Set-up of a new scene (docs/performance.md, "Set-up"), one render of 1 pass each.
# usage (from the repository root): docs/measurements/setup/setup.sh LABEL=BINARY ...
# For each scene, each binary in turn (interleaved): cold (fresh ppm-vk and Mesa caches), then warm (the
# same caches again). SCENES overrides the list; matpreview is read from a mitsuba-data checkout
# (MITSUBA_DATA, default /work/mitsuba-data), never committed here.
export XDG_RUNTIME_DIR=/tmp; echo "load: $(cat /proc/loadavg)"
SCENES=${SCENES:-"scenes/cornell-spheres.toml scenes/cornell-mesh.toml scenes/glass-on-table.toml scenes/textured-params.xml ${MITSUBA_DATA:-/work/mitsuba-data}/scenes/matpreview/matpreview.xml"}
for s in $SCENES; do
  for lb in "$@"; do
    L=${lb%%=*}; BIN=${lb#*=}
    T=$(mktemp -d); export PPM_VK_CACHE_DIR=$T/ppm MESA_SHADER_CACHE_DIR=$T/mesa
    for run in cold warm; do
      s0=$(date +%s.%N)
      out=$($BIN render $s --passes 1 --photons-per-pass 100000 --resolution 128x128 -o $T/o.exr -f --profile 2>&1)
      s1=$(date +%s.%N)
      echo "$L $(basename $s) $run process=$(printf %.2f $(echo "$s1-$s0"|bc)) $(echo "$out" | grep -o 'in [0-9.]* s (.*setup [0-9.]* s' | sed 's/(.*;//') $(echo "$out" | grep -o 'ray pass [0-9.]* ms')"
      echo "$out" | grep -A9 '^set-up' | sed 's/^/    /'
    done
    rm -rf $T
  done
done
echo "load: $(cat /proc/loadavg)"
