cd "$(dirname "$0")/../../../.."; export XDG_RUNTIME_DIR=/tmp
for s in cornell-aniso cornell-rough cornell-gold; do for v in off curvature; do
 target/release/ppm-vk render scenes/references/$s.xml -D res=256 --probe $v --passes 16 --reference scenes/references/$s.exr --error-every 16 -o docs/measurements/issue38/equal-passes/$s-$v.exr -f > docs/measurements/issue38/equal-passes/$s-$v.txt 2>&1
done; done; echo done > docs/measurements/issue38/equal-passes/more-done
