#!/usr/bin/env python3
"""Loads and renders public Mitsuba scenes as they are published, with ppm-vk and with Mitsuba 3.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        python3 docs/measurements/public-scenes/check.py /path/to/mitsuba-data \
        --ppm-vk target/release/ppm-vk --out /tmp/public-scenes [--render] [--only NAME ...]

The scenes are not ours to commit: give a checkout of Mitsuba's `mitsuba-data` repository (its
`scenes/`, `tests/scenes/` and `docs/scenes/` are read; fragments and include folders are skipped,
they are not scenes by themselves). For every file this prints whether ppm-vk reads it (and its first
error where it does not), and with `--render`, for those it reads, ppm-vk's image mean per channel
against Mitsuba 3's path tracer given the same file (its own integrator replaced by `path` with
unlimited depth, since ppm-vk renders every light path; several of Mitsuba's test scenes limit the
depth to 2 to test one bounce). Both render at the file's own resolution, capped at 128 pixels
wide (`-D`-free: the width and height are set through Mitsuba's film after loading, and through
`--resolution` for ppm-vk). The table is written to OUT/table.md and the images beside it.
"""

import argparse
import json
import os
import subprocess
import sys
import time

SKIP_DIRS = ("fragments", "include", "principled_blend_creation")


def scenes(root):
    found = []
    for top in ("scenes", "tests/scenes", "docs/scenes"):
        for dirpath, dirnames, files in os.walk(os.path.join(root, top)):
            dirnames[:] = sorted(d for d in dirnames if d not in SKIP_DIRS and d != "refs")
            for f in sorted(files):
                if f.endswith(".xml"):
                    found.append(os.path.join(dirpath, f))
    return found


def first_error(text):
    for line in text.splitlines():
        if line.startswith("error"):
            return line[:300]
    lines = [l for l in text.splitlines() if l.strip()]
    return (lines[-1] if lines else "")[:300]


def mean_exr(path):
    import numpy as np
    import mitsuba as mi

    return np.array(mi.Bitmap(path)).reshape(-1, 3).astype(np.float64).mean(axis=0)


def mitsuba_render(path, size, spp, out, integrator="path"):
    import mitsuba as mi

    scene = mi.load_file(path)
    sensor = scene.sensors()[0]
    params = mi.traverse(sensor)
    params["film.size"] = list(size)
    params.update()
    integrator = mi.load_dict({"type": integrator, "max_depth": -1})
    image = mi.render(scene, sensor=sensor, integrator=integrator, spp=spp, seed=7)
    mi.Bitmap(image).write(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data", help="a checkout of mitsuba-data")
    ap.add_argument("--ppm-vk", default="target/release/ppm-vk")
    ap.add_argument("--out", default="/tmp/public-scenes")
    ap.add_argument("--render", action="store_true", help="also render those that load, with both")
    ap.add_argument("--passes", type=int, default=64)
    ap.add_argument("--photons", type=int, default=200000)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--max-width", type=int, default=128)
    ap.add_argument("--only", nargs="*", default=None, help="substrings of the files to try")
    ap.add_argument("--integrator", default="path",
                    help="Mitsuba's integrator (volpath for masks: its path takes a mask as opaque to shadow rays)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.render:
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")

    rows, loaded = [], 0
    files = scenes(args.data)
    if args.only:
        files = [f for f in files if any(o in f for o in args.only)]
    for path in files:
        rel = os.path.relpath(path, args.data)
        name = rel.replace("/", "_")[:-4]
        # `check` reads the file as `render` does, without a device: the cheap "does it read".
        check = subprocess.run([args.ppm_vk, "check", path], capture_output=True, text=True, timeout=600)
        if check.returncode != 0:
            why = next((l for l in check.stdout.splitlines() if l.startswith("error")), check.stderr)[:300]
            rows.append({"file": rel, "status": "refused", "why": why})
            print(f"refused  {rel}: {why}", flush=True)
            continue
        loaded += 1
        warnings = [l.strip() for l in check.stdout.splitlines() if l.strip().startswith("warning")]
        row = {"file": rel, "status": "reads", "warnings": warnings}
        if args.render:
            try:
                import mitsuba as mi

                film = mi.traverse(mi.load_file(path).sensors()[0])["film.size"]
                w, h = int(film[0]), int(film[1])
                if w > args.max_width:
                    w, h = args.max_width, max(1, round(h * args.max_width / w))
                ours = os.path.join(args.out, name + "-ppm-vk.exr")
                theirs = os.path.join(args.out, name + "-mitsuba.exr")
                t0 = time.time()
                r = subprocess.run(
                    [args.ppm_vk, "render", path, "--passes", str(args.passes), "--photons-per-pass",
                     str(args.photons), "--resolution", f"{w}x{h}", "--out", ours, "-f"],
                    capture_output=True, text=True, timeout=3600,
                )
                t1 = time.time()
                if r.returncode != 0:
                    row.update(status="render failed", why=first_error(r.stderr))
                else:
                    mitsuba_render(path, (w, h), args.spp, theirs, args.integrator)
                    t2 = time.time()
                    a, b = mean_exr(ours), mean_exr(theirs)
                    row.update(
                        size=f"{w}x{h}",
                        ppm_vk_mean=[round(x, 6) for x in a],
                        mitsuba_mean=[round(x, 6) for x in b],
                        ratio=[round(x / y, 4) if y > 0 else None for x, y in zip(a, b)],
                        ppm_vk_s=round(t1 - t0, 1),
                        mitsuba_s=round(t2 - t1, 1),
                    )
            except Exception as e:  # a scene Mitsuba itself cannot render here (a missing file, a variant)
                row.update(status="reads; reference failed", why=str(e).splitlines()[0][:300])
        print(f"{row['status']:8} {rel}: {json.dumps({k: v for k, v in row.items() if k not in ('file', 'status')})}",
              flush=True)
        rows.append(row)

    with open(os.path.join(args.out, "table.md"), "w") as f:
        f.write(f"{loaded} of {len(files)} files read\n\n| file | status | detail |\n|---|---|---|\n")
        for r in rows:
            detail = r.get("why") or (f"ratio {r['ratio']}, {r['size']}" if "ratio" in r else f"{len(r.get('warnings', []))} warnings")
            f.write(f"| {r['file']} | {r['status']} | {detail} |\n")
    with open(os.path.join(args.out, "table.json"), "w") as f:
        json.dump(rows, f, indent=1)
    print(f"{loaded} of {len(files)} files read; table in {args.out}/table.md")


if __name__ == "__main__":
    sys.exit(main())
