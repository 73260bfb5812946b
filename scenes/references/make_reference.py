#!/usr/bin/env python3
"""Independent reference renders with Mitsuba 3's path tracer, for scenes of this folder.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        python3 scenes/references/make_reference.py glass-on-table --chunks 16 --spp 512 [--res 256]
    ... make_reference.py env-window --chunks 8 --spp 256 --size 160x120
    ... make_reference.py spot-caustic --chunks 8 --spp 64 --integrator hybrid --note "..."

NAME.xml is looked for in this folder, then in scenes/ (the lights' scenes, issue 36); the outputs are
always written here. `--res N` sets the XML's `$res` (width = height); `--size WxH` sets its `$width` and
`$height` instead, for a scene that declares those.

`--integrator path` (the default) renders with the XML's own integrator (Mitsuba's path tracer). It
never finds light that leaves a delta light (point, spot) and meets a smooth specular surface (glass,
mirror) before its first diffuse or glossy bounce: a caustic of a point or spot light. `--integrator
hybrid` adds those: each chunk is Mitsuba's particle tracer (`ptracer`, light paths connected to the
camera at every non-specular vertex: all light whose first surface seen from the camera is not smooth)
plus Mitsuba's path tracer counted only on camera rays whose first hit is a smooth specular (delta) bsdf,
so every path is counted exactly once, except light that leaves the delta light through smooth surfaces
before a diffuse bounce and is then seen through smooth surfaces (L S+ D ... S+ E: a caustic seen through
the glass), which neither counts. Both use the same seed.

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

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")  # before FirstHitDelta below, which subclasses a variant's class

HERE = os.path.dirname(os.path.abspath(__file__))


def split_obj(src, out_dir):
    """Writes each object ('o name') of an OBJ of positions, normals and faces as its own OBJ, with the
    vertex normals the faces name (smooth shading, as ppm-vk renders the demo mesh)."""
    os.makedirs(out_dir, exist_ok=True)
    positions, normals, objects, current = [], [], {}, None
    for line in open(src):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            positions.append(line)
        elif parts[0] == "vn":
            normals.append(line)
        elif parts[0] == "o":
            current = parts[1]
            objects[current] = []
        elif parts[0] == "f":
            # v//vn or v/vt/vn -> (v, vn); v alone -> (v, None)
            corners = []
            for c in parts[1:]:
                fields = c.split("/")
                corners.append((int(fields[0]), int(fields[2]) if len(fields) > 2 and fields[2] else None))
            objects[current].append(corners)
    for name, faces in objects.items():
        used_v = sorted({v for f in faces for v, _ in f})
        used_n = sorted({n for f in faces for _, n in f if n is not None})
        remap_v = {old: new + 1 for new, old in enumerate(used_v)}
        remap_n = {old: new + 1 for new, old in enumerate(used_n)}
        with open(os.path.join(out_dir, name + ".obj"), "w") as f:
            f.write(f"# {name}, split from {os.path.basename(src)} by make_reference.py\n")
            for i in used_v:
                f.write(positions[i - 1])
            for i in used_n:
                f.write(normals[i - 1])
            for face in faces:
                f.write(
                    "f "
                    + " ".join(f"{remap_v[v]}//{remap_n[n]}" if n is not None else str(remap_v[v]) for v, n in face)
                    + "\n"
                )


class FirstHitDelta(mi.SamplingIntegrator):
    """Mitsuba's path tracer, counted only where the camera ray first hits a smooth (delta) bsdf."""

    def __init__(self, props):
        super().__init__(props)
        self.inner = mi.load_dict({"type": "path", "max_depth": -1})

    def sample(self, scene, sampler, ray, medium=None, active=True):
        si = scene.ray_intersect(mi.Ray3f(ray), active)
        delta = si.is_valid() & mi.has_flag(si.bsdf().flags(), mi.BSDFFlags.Delta)
        L, valid, aovs = self.inner.sample(scene, sampler, ray, medium, active)
        return dr.select(delta, L, 0.0), valid, aovs

    def aov_names(self):
        return []

    def to_string(self):
        return "FirstHitDelta[path]"


def render_chunk(scene, integrators, spp, seed):
    total = None
    for integrator in integrators:
        img = np.array(mi.render(scene, integrator=integrator, spp=spp, seed=seed), dtype=np.float64)
        total = img if total is None else total + img
    return total


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("name", help="scene name: NAME.xml in this folder, else in scenes/")
    p.add_argument("--chunks", type=int, default=16)
    p.add_argument("--spp", type=int, default=512)
    p.add_argument("--res", type=int, default=256, help="the XML's $res: width = height")
    p.add_argument("--size", help="WxH: the XML's $width and $height instead of $res")
    p.add_argument("--integrator", choices=["path", "hybrid"], default="path")
    p.add_argument("--note", action="append", default=[], help="a line appended to NAME.txt (repeatable)")
    a = p.parse_args()
    if a.name == "glass-on-table":
        split_obj(os.path.join(HERE, "..", "meshes", "glass-on-table.obj"), os.path.join(HERE, "meshes"))
    xml = os.path.join(HERE, a.name + ".xml")
    where = f"{a.name}.xml"
    if not os.path.exists(xml):
        xml = os.path.join(HERE, "..", a.name + ".xml")
        where = f"scenes/{a.name}.xml"
    if a.size:
        w, h = (int(v) for v in a.size.lower().split("x"))
        scene = mi.load_file(xml, width=w, height=h)
        size = f"{w}x{h}"
    else:
        scene = mi.load_file(xml, res=a.res)
        size = f"{a.res}x{a.res}"
    if a.integrator == "hybrid":
        mi.register_integrator("first_hit_delta", lambda props: FirstHitDelta(props))
        integrators = [
            mi.load_dict({"type": "ptracer", "max_depth": -1}),
            mi.load_dict({"type": "first_hit_delta"}),
        ]
        how = ("hybrid integrator (Mitsuba's ptracer + its path tracer where the camera first hits a smooth "
               "bsdf; make_reference.py's docstring)")
    else:
        integrators = [scene.integrator()]
        how = "path integrator"
    images = []
    start = time.perf_counter()
    for k in range(a.chunks):
        t0 = time.perf_counter()
        images.append(render_chunk(scene, integrators, a.spp, 1000 + k))
        print(f"chunk {k + 1}/{a.chunks}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    var = stack.var(axis=0, ddof=1) / a.chunks
    out = os.path.join(HERE, a.name)
    mi.Bitmap(mean.astype(np.float32)).write(out + ".exr")
    mi.Bitmap(var.astype(np.float32)).write(out + "_var.exr")
    with open(out + ".txt", "w") as f:
        f.write(
            f"{where} at {size}: {a.chunks} chunks of {a.spp} spp ({a.chunks * a.spp} in all), "
            f"seeds 1000-{999 + a.chunks}, Mitsuba {mi.__version__} {mi.variant()}, {how}, "
            f"{time.perf_counter() - start:.0f} s on this machine\n"
            f"mean RGB {mean.reshape(-1, 3).mean(axis=0)}, mean variance of the mean {var.mean():.3g}\n"
        )
        for line in a.note:
            f.write(line + "\n")


if __name__ == "__main__":
    main()
