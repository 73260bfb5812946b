#!/usr/bin/env python3
"""Mitsuba 3's shading frames on the shapes of tangents.xml, for ppm-vk's tests of anisotropic roughness.

Writes tangents.json beside this script: for each shape (its id, at x = 0, 4, 8, 12, 16, 20), rays from 24
fixed pseudo-random points on a sphere of radius 3 about its centre (random.Random(7)) towards points near
the centre (within 0.3), and where a ray hits the shape: the ray (o, d), the hit p, Mitsuba's shading normal
sh_frame.n and its tangent sh_frame.s (dp/du made orthogonal to the shading normal), which an anisotropic
lobe's alpha_u lies along. Rays that miss, or hit another shape, are left out.

Run: pip install mitsuba; python3 scenes/references/tangents.py   (a few seconds)
"""
import json
import math
import os
import random

import mitsuba as mi

mi.set_variant("scalar_rgb")
HERE = os.path.dirname(os.path.abspath(__file__))
SHAPES = [("sphere", 0.0), ("rectangle", 4.0), ("flipped", 8.0), ("mirrored", 12.0), ("box", 16.0), ("mesh", 20.0)]


def main():
    # optimize=False: Mitsuba would merge shapes with equal bsdfs into one mesh.
    scene = mi.load_file(os.path.join(HERE, "tangents.xml"), optimize=False)
    ids = {s.id(): s for s in scene.shapes()}
    rnd = random.Random(7)
    out = []
    for name, x in SHAPES:
        shape = ids[name]
        hits = []
        for _ in range(24):
            z, phi = rnd.uniform(-1, 1), rnd.uniform(0, 2 * math.pi)
            r = math.sqrt(1 - z * z)
            o = [x + 3 * r * math.cos(phi), 3 * r * math.sin(phi), 3 * z]
            t = [x + rnd.uniform(-0.3, 0.3), rnd.uniform(-0.3, 0.3), rnd.uniform(-0.3, 0.3)]
            d = [t[i] - o[i] for i in range(3)]
            n = math.sqrt(sum(c * c for c in d))
            d = [c / n for c in d]
            si = scene.ray_intersect(mi.Ray3f(mi.Point3f(o), mi.Vector3f(d)))
            if not si.is_valid() or si.shape.id() != name:
                continue
            hits.append({
                "o": o,
                "d": d,
                "p": list(si.p),
                "n": list(si.sh_frame.n),
                "s": list(si.sh_frame.s),
            })
        out.append({"shape": name, "hits": hits})
    doc = {"mitsuba_version": mi.__version__, "variant": "scalar_rgb", "shapes": out}
    with open(os.path.join(HERE, "tangents.json"), "w") as f:
        json.dump(doc, f, indent=1)
    print({s["shape"]: len(s["hits"]) for s in out})


if __name__ == "__main__":
    main()
