cd "$(dirname "$0")/../../../.."; export XDG_RUNTIME_DIR=/tmp
o=docs/measurements/issue38/curvature-30s
target/release/ppm-vk compare scenes/glass-on-table.toml --reference scenes/references/glass-on-table.exr --resolution 256x256 --time 30 --variants "sppm; sppm+probe-curv=1" --out $o/shrink-got > $o/shrink-got.log 2>&1
target/release/ppm-vk compare scenes/cornell-spheres.toml --reference ../shared/reference/cornell-spheres.exr --time 30 --variants "sppm; sppm+probe-curv=1" --out $o/shrink-cs > $o/shrink-cs.log 2>&1
target/release/ppm-vk compare scenes/references/cornell-rough.xml -D res=256 --reference scenes/references/cornell-rough.exr --time 30 --variants "sppm; sppm+probe-curv=1" --out $o/shrink-rough > $o/shrink-rough.log 2>&1
target/release/ppm-vk compare scenes/cornell-box.toml --reference scenes/references/cornell-box.exr --resolution 256x256 --time 30 --variants "sppm; sppm+probe-curv=1" --out $o/shrink-cb > $o/shrink-cb.log 2>&1
echo done > $o/done
