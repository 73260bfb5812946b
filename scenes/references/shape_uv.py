#!/usr/bin/env python3
"""Mitsuba 3's texture coordinates on its cylinder, disk and cube, for ppm-vk's tests of the meshes it makes
of them.

Writes shape-uv.json beside this script: for each case (a shape's dict: its type, its parameters and
to_world, given below as XML too), where rays from 40 fixed pseudo-random points on a sphere about the
shape (random.Random(11)) towards points near its centre hit it: the hit p, Mitsuba's uv and shading
normal there. ppm-vk's mesh of the shape, at the point of its surface nearest p, must have that uv.

Run: pip install mitsuba; python3 scenes/references/shape_uv.py   (a few seconds)
"""
import json
import math
import os
import random

import mitsuba as mi

mi.set_variant("scalar_rgb")
HERE = os.path.dirname(os.path.abspath(__file__))

# (name, Mitsuba's dict without to_world, to_world as XML steps, the same as a ScalarTransform4f)
T = mi.ScalarTransform4f
CASES = [
    ("cylinder", {"type": "cylinder"}, "", T()),
    ("cylinder p0 p1 radius",
     {"type": "cylinder", "p0": [1.0, -0.5, 0.25], "p1": [-0.5, 2.0, 1.0], "radius": 0.3},
     '<point name="p0" value="1, -0.5, 0.25"/><point name="p1" value="-0.5, 2, 1"/><float name="radius" value="0.3"/>',
     T()),
    ("cylinder down the z axis", {"type": "cylinder", "p0": [0.0, 0.0, 1.0], "p1": [0.0, 0.0, -1.0]},
     '<point name="p0" value="0, 0, 1"/><point name="p1" value="0, 0, -1"/>', T()),
    ("cylinder to_world", {"type": "cylinder", "radius": 0.5},
     '<float name="radius" value="0.5"/><transform name="to_world"><scale value="2"/>'
     '<rotate x="0.6" y="0.8" angle="70"/><translate x="1" y="2" z="3"/></transform>',
     T().translate([1, 2, 3]) @ T().rotate([0.6, 0.8, 0], 70) @ T().scale(2)),
    ("disk", {"type": "disk"}, "", T()),
    ("disk to_world", {"type": "disk"},
     '<transform name="to_world"><scale x="2" y="0.5"/><rotate y="1" angle="40"/><translate z="1"/></transform>',
     T().translate([0, 0, 1]) @ T().rotate([0, 1, 0], 40) @ T().scale([2, 0.5, 1])),
    ("cube", {"type": "cube"}, "", T()),
    ("cube to_world", {"type": "cube"},
     '<transform name="to_world"><scale x="0.5" y="1" z="2"/><rotate x="0.6" y="0.8" angle="70"/></transform>',
     T().rotate([0.6, 0.8, 0], 70) @ T().scale([0.5, 1, 2])),
    ("cube mirrored", {"type": "cube", "flip_normals": True},
     '<boolean name="flip_normals" value="true"/><transform name="to_world"><scale x="-1"/></transform>',
     T().scale([-1, 1, 1])),
]


def main():
    rnd = random.Random(11)
    out = []
    for name, d, xml, to_world in CASES:
        shape = mi.load_dict(dict(d, to_world=to_world))
        scene = mi.load_dict({"type": "scene", "s": shape})
        box = shape.bbox()
        c, reach = box.center(), 2 * dr_norm(box.extents())
        hits = []
        for _ in range(40):
            z, phi = rnd.uniform(-1, 1), rnd.uniform(0, 2 * math.pi)
            r = math.sqrt(1 - z * z)
            o = [c[0] + reach * r * math.cos(phi), c[1] + reach * r * math.sin(phi), c[2] + reach * z]
            t = [c[i] + rnd.uniform(-0.2, 0.2) * box.extents()[i] for i in range(3)]
            dvec = [t[i] - o[i] for i in range(3)]
            si = scene.ray_intersect(mi.Ray3f(mi.Point3f(o), mi.Vector3f(dvec)))
            if not si.is_valid():
                continue
            hits.append({"p": list(si.p), "uv": list(si.uv), "n": list(si.sh_frame.n)})
        out.append({"name": name, "type": d["type"], "xml": xml, "hits": hits})
    doc = {"mitsuba_version": mi.__version__, "variant": "scalar_rgb", "cases": out}
    with open(os.path.join(HERE, "shape-uv.json"), "w") as f:
        json.dump(doc, f, indent=1)
    print([(c["name"], len(c["hits"])) for c in out])


def dr_norm(v):
    return math.sqrt(sum(x * x for x in v))


if __name__ == "__main__":
    main()
