#!/usr/bin/env python3
"""Mitsuba 3's file resolution, for ppm-vk's reader (crates/scene/src/mitsuba/xml.rs's test of <path> and includes).

Builds in a temporary folder the files that test builds: t.spd (a flat spectrum of 0.4) beside the scene,
a/t.spd (0.2) and b/t.spd (0.6); the scene reads `t.spd` as a reflectance before any <path>, after
<path value="a"/>, and after <path value="b"/>; it includes include/a.xml, which includes "include/b.xml"
(found from the scene's folder, as in mitsuba-data's participating_media scenes), which reads `t.spd` too.
Writes file-resolver.json beside this script: the RGB Mitsuba made of each (`scalar_rgb`, mi.traverse).

Run: pip install mitsuba; DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 scenes/references/file_resolver.py
"""
import json
import os
import tempfile

import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))

mi.set_variant("scalar_rgb")
with tempfile.TemporaryDirectory() as d:
    for sub, value in [("", 0.4), ("a", 0.2), ("b", 0.6)]:
        os.makedirs(os.path.join(d, sub), exist_ok=True)
        with open(os.path.join(d, sub, "t.spd"), "w") as f:
            f.write(f"360 {value}\n830 {value}\n")
    os.makedirs(os.path.join(d, "include"))
    with open(os.path.join(d, "include", "a.xml"), "w") as f:
        f.write('<scene version="3.0.0"><include filename="include/b.xml"/></scene>')
    with open(os.path.join(d, "include", "b.xml"), "w") as f:
        f.write('<scene version="3.0.0"><bsdf type="diffuse" id="included">'
                '<spectrum name="reflectance" filename="t.spd"/></bsdf></scene>')
    bsdf = '<bsdf type="diffuse" id="{}"><spectrum name="reflectance" filename="t.spd"/></bsdf>'
    with open(os.path.join(d, "scene.xml"), "w") as f:
        f.write('<scene version="3.0.0">' + bsdf.format("before") + '<path value="a"/>' + bsdf.format("after_a")
                + '<path value="b"/>' + bsdf.format("after_b") + '<include filename="include/a.xml"/>'
                + '<shape type="sphere"><ref id="included"/></shape></scene>')
    # optimize=False: identical bsdfs are not merged into one (the included one equals "before").
    params = mi.traverse(mi.load_file(os.path.join(d, "scene.xml"), optimize=False))
    out = {k.split(".")[0]: [float(params[k][i]) for i in range(3)]
           for k in params.keys() if k.endswith("reflectance.value")}

with open(os.path.join(HERE, "file-resolver.json"), "w") as f:
    json.dump(out, f, indent=1)
    f.write("\n")
print(json.dumps(out, indent=1))
