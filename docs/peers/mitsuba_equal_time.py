#!/usr/bin/env python3
"""Mitsuba 3's path tracer at equal wall time, scored as ppm-vk scores its renders.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        python3 docs/peers/mitsuba_equal_time.py SCENE.xml REFERENCE.exr --seconds 10 30 60 --csv out.csv

For each budget it finds the samples per pixel that take that long on this machine (from a timed render
at a few spp: the clock counts the render call, kernel compilation included, not Python's start or the
scene's loading), renders `--runs` times with seeds unlike the reference's, and prints RMSE and relMSE
against the reference with the reference's own noise removed (its `_var.exr` beside it), as
crates/engine/src/metrics.rs defines them: RMSE = sqrt(mean((x - ref)^2) - mean(var)), relMSE =
mean((x - ref)^2 / (ref^2 + 0.01)) - mean(var / (ref^2 + 0.01)). `--region NAME=x0,y0,x1,y1` (pixels,
origin top left, exclusive ends) scores a box too. Needs `pip install mitsuba numpy` and, on Debian 12,
libllvm19 (../shared/notes/TOOLCHAIN.md).
"""

import argparse
import os
import sys
import time

import numpy as np

import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

REL_EPSILON = 0.01


def load_exr(path):
    return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32), dtype=np.float64)


def score(img, ref, var, box=None):
    if box is not None:
        x0, y0, x1, y1 = box
        img, ref = img[y0:y1, x0:x1], ref[y0:y1, x0:x1]
        var = None if var is None else var[y0:y1, x0:x1]
    d2 = (img - ref) ** 2
    w = 1.0 / (ref**2 + REL_EPSILON)
    mse, rel = d2.mean(), (d2 * w).mean()
    if var is not None:
        mse, rel = max(mse - var.mean(), 0.0), max(rel - (var * w).mean(), 0.0)
    return np.sqrt(mse), rel


def render(scene, spp, seed):
    start = time.perf_counter()
    img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
    return img, time.perf_counter() - start


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene")
    p.add_argument("reference")
    p.add_argument("--seconds", type=float, nargs="+", default=[10, 30, 60])
    p.add_argument("--runs", type=int, default=2)
    p.add_argument("--region", action="append", default=[], help="NAME=x0,y0,x1,y1")
    p.add_argument("--csv", help="append seconds,rel_mse,label rows (the mean of the runs) for compare --peer")
    p.add_argument("--label", default="Mitsuba path")
    p.add_argument("--threads", type=int, default=0, help="Dr.Jit threads (0: all cores)")
    p.add_argument("--res", type=int, help="the scene's $res parameter (its image width and height), if it has one")
    a = p.parse_args()
    if a.threads:
        import drjit as dr

        dr.set_thread_count(a.threads)
    ref = load_exr(a.reference)
    stem, ext = os.path.splitext(a.reference)
    var = load_exr(stem + "_var" + ext) if os.path.exists(stem + "_var" + ext) else None
    regions = []
    for r in a.region:
        name, box = r.split("=")
        regions.append((name, tuple(int(v) for v in box.split(","))))
    scene = mi.load_file(a.scene, **({"res": a.res} if a.res else {}))
    # Calibration: time per sample per pixel from a short and a longer render (the fixed cost is the
    # kernel compilation and the image's development).
    render(scene, 4, 1000)  # the first call compiles
    _, t1 = render(scene, 16, 1001)
    _, t2 = render(scene, 64, 1002)
    per_spp = max((t2 - t1) / 48.0, 1e-6)
    fixed = max(t1 - 16 * per_spp, 0.0)
    print(f"# {a.scene}: {per_spp * 1e3:.2f} ms per spp, {fixed:.2f} s fixed", file=sys.stderr)
    header = "seconds,spp,run,wall_s,rmse,rel_mse" + "".join(f",{n}_rmse,{n}_rel_mse" for n, _ in regions)
    print(header)
    rows = []
    for seconds in a.seconds:
        spp = max(1, int((seconds - fixed) / per_spp))
        rels = []
        for run in range(a.runs):
            img, wall = render(scene, spp, 7919 * (run + 1) + int(seconds))
            rmse, rel = score(img, ref, var)
            extra = "".join(",%.5g,%.5g" % score(img, ref, var, box) for _, box in regions)
            print(f"{seconds:g},{spp},{run},{wall:.2f},{rmse:.5g},{rel:.5g}{extra}", flush=True)
            rels.append(rel)
        rows.append((seconds, float(np.mean(rels))))
    if a.csv:
        with open(a.csv, "a") as f:
            for seconds, rel in rows:
                f.write(f"{seconds:g},{rel:.5g},{a.label}\n")


if __name__ == "__main__":
    main()
