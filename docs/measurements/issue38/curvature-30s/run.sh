cd "$(dirname "$0")/../../../.."; export XDG_RUNTIME_DIR=/tmp
target/release/ppm-vk compare scenes/glass-on-table.toml --reference scenes/references/glass-on-table.exr --resolution 256x256 --time 30 --variants "sppm; sppm+probe-curv; sppm+probe-nn" --out docs/measurements/issue38/curvature-30s/got > docs/measurements/issue38/curvature-30s/got.log 2>&1
target/release/ppm-vk compare scenes/cornell-spheres.toml --reference ../shared/reference/cornell-spheres.exr --time 30 --variants "sppm; sppm+probe-curv" --out docs/measurements/issue38/curvature-30s/cs > docs/measurements/issue38/curvature-30s/cs.log 2>&1
target/release/ppm-vk compare scenes/references/cornell-rough.xml -D res=256 --reference scenes/references/cornell-rough.exr --time 30 --variants "sppm; sppm+probe-curv" --out docs/measurements/issue38/curvature-30s/rough > docs/measurements/issue38/curvature-30s/rough.log 2>&1
echo done > docs/measurements/issue38/curvature-30s/done
