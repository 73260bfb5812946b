#!/usr/bin/env python3
"""Independent reference renders with Mitsuba 3's path tracer, for scenes of this folder.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        python3 scenes/references/make_reference.py glass-on-table --chunks 16 --spp 512 [--res 256]

Renders `--chunks` independent images of `--spp` samples per pixel (seeds 1000 + k, unlike compare's and
mitsuba_equal_time.py's) and writes NAME.exr (their mean) and NAME_var.exr (the per-pixel variance of that
mean, from the spread between the chunks: the reference's own noise, which ppm-vk's metrics subtract),
and NAME.txt (what was rendered, how long it took). Splits the demo mesh scenes/meshes/glass-on-table.obj
into meshes/table.obj and meshes/torus.obj first (its two objects; the XML gives each its bsdf). Needs
`pip install mitsuba numpy` and, on Debian 12, libllvm19 (../shared/notes/TOOLCHAIN.md).
"""

import argparse
import os
import sys
import time

import numpy as np

import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))


def split_obj(src, out_dir):
    """Writes each object ('o name') of an OBJ of positions and faces as its own OBJ (flat faces)."""
    os.makedirs(out_dir, exist_ok=True)
    positions, objects, current = [], {}, None
    for line in open(src):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            positions.append(line)
        elif parts[0] == "o":
            current = parts[1]
            objects[current] = []
        elif parts[0] == "f":
            # keep the vertex indices only (v/vt/vn -> v): flat shading
            objects[current].append([int(p.split("/")[0]) for p in parts[1:]])
    for name, faces in objects.items():
        used = sorted({i for f in faces for i in f})
        remap = {old: new + 1 for new, old in enumerate(used)}
        with open(os.path.join(out_dir, name + ".obj"), "w") as f:
            f.write(f"# {name}, split from {os.path.basename(src)} by make_reference.py\n")
            for i in used:
                f.write(positions[i - 1])
            for face in faces:
                f.write("f " + " ".join(str(remap[i]) for i in face) + "\n")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("name", help="scene name: NAME.xml in this folder")
    p.add_argument("--chunks", type=int, default=16)
    p.add_argument("--spp", type=int, default=512)
    p.add_argument("--res", type=int, default=256)
    a = p.parse_args()
    mi.set_variant("llvm_ad_rgb")
    if a.name == "glass-on-table":
        split_obj(os.path.join(HERE, "..", "meshes", "glass-on-table.obj"), os.path.join(HERE, "meshes"))
    xml = os.path.join(HERE, a.name + ".xml")
    scene = mi.load_file(xml, res=a.res)
    images = []
    start = time.perf_counter()
    for k in range(a.chunks):
        t0 = time.perf_counter()
        images.append(np.array(mi.render(scene, spp=a.spp, seed=1000 + k), dtype=np.float64))
        print(f"chunk {k + 1}/{a.chunks}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    var = stack.var(axis=0, ddof=1) / a.chunks
    out = os.path.join(HERE, a.name)
    mi.Bitmap(mean.astype(np.float32)).write(out + ".exr")
    mi.Bitmap(var.astype(np.float32)).write(out + "_var.exr")
    with open(out + ".txt", "w") as f:
        f.write(
            f"{a.name}.xml at {a.res}x{a.res}: {a.chunks} chunks of {a.spp} spp ({a.chunks * a.spp} in all), "
            f"seeds 1000-{999 + a.chunks}, Mitsuba {mi.__version__} {mi.variant()}, path integrator, "
            f"{time.perf_counter() - start:.0f} s on this machine\n"
            f"mean RGB {mean.reshape(-1, 3).mean(axis=0)}, mean variance of the mean {var.mean():.3g}\n"
        )


if __name__ == "__main__":
    main()
