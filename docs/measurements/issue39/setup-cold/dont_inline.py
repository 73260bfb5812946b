#!/usr/bin/env python3
"""spirv-opt -O on the ray kernel with some functions marked DontInline (docs/performance.md, "Set-up: where
a cold start's seconds go"). Input: DIR/ray-zero.spv, written by a build with dump.patch applied:
  PPM_VK_DUMP=DIR PPM_VK_CACHE_DIR=$(mktemp -d) MESA_SHADER_CACHE_DIR=$(mktemp -d) \
    target/release/ppm-vk render scenes/interior.xml --passes 1 --resolution 160x90 -o /tmp/o.exr -f
Usage: dont_inline.py DIR   (needs spirv-dis, spirv-as, spirv-opt: Debian's spirv-tools)"""
import re, subprocess, sys, time

d = sys.argv[1]
subprocess.run(["spirv-dis", f"{d}/ray-zero.spv", "-o", f"{d}/ray-zero.dis"], check=True)
dis = open(f"{d}/ray-zero.dis").read()
names = dict(re.findall(r'OpName (%\S+) "([^"(]*)', dis))
variants = {
    "none": set(),
    "texture_value": {"texture_value"},
    "trace_scene": {"trace_scene"},
    "both": {"texture_value", "trace_scene"},
    "seven": {"texture_value", "trace_scene", "light_sample", "lobe_bounce", "rough_lobe", "surface_uv", "mf_g1"},
}
for tag, fns in variants.items():
    out = []
    for line in dis.split("\n"):
        m = re.match(r"\s*(%\S+) = OpFunction (%\S+) None", line)
        if m and names.get(m.group(1)) in fns:
            line = line.replace(" None ", " DontInline ")
        out.append(line)
    open(f"{d}/v-{tag}.dis", "w").write("\n".join(out))
    subprocess.run(["spirv-as", "--target-env", "vulkan1.2", f"{d}/v-{tag}.dis", "-o", f"{d}/v-{tag}.spv"], check=True)
    t0 = time.time()
    subprocess.run(["spirv-opt", "-O", f"{d}/v-{tag}.spv", "-o", f"{d}/v-{tag}-o.spv"], check=True)
    print(f"{tag}: spirv-opt -O {time.time() - t0:.2f} s")
