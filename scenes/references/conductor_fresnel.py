#!/usr/bin/env python3
"""Mitsuba 3's conductor, as its RGB variants define it, for ppm-vk's tests and tables.

Prints (1) the named materials' RGB eta and k that Mitsuba's scalar_rgb variant loads from its spectral
data (crates/materials/src/conductor.rs holds them), and (2) writes conductor-fresnel.json beside this
script: the weight Mitsuba's conductor BSDF returns when sampled (specular_reflectance times the conductor
Fresnel term) at several angles, for named and explicit eta/k, which the engine's tests compare its own
Fresnel term against.

Run: pip install mitsuba numpy; python3 scenes/references/conductor_fresnel.py
"""
import json
import math
import os

import mitsuba as mi

mi.set_variant("scalar_rgb")

NAMED = ["a-C", "Ag", "Al", "AlAs", "AlSb", "Au", "Be", "Cr", "CsI", "Cu", "Cu2O", "CuO", "d-C", "Hg",
         "HgTe", "Ir", "K", "Li", "MgO", "Mo", "Na_palik", "Nb", "Ni_palik", "Rh", "Se", "SiC", "SnTe", "Ta",
         "Te", "ThF4", "TiC", "TiN", "TiO2", "VC", "V_palik", "VN", "W"]

print("// name, eta, k: Mitsuba 3.9.1 scalar_rgb")
for name in NAMED:
    p = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
    eta, k = p["eta.value"], p["k.value"]
    fmt = lambda v: "[" + ", ".join(f"{float(v[i]):.6}" for i in range(3)) + "]"
    print(f'    ("{name}", {fmt(eta)}, {fmt(k)}),')

CASES = [
    {"type": "conductor"},
    {"type": "conductor", "material": "Au"},
    {"type": "conductor", "material": "Cu"},
    {"type": "conductor", "material": "Al"},
    {"type": "conductor", "material": "Cr"},
    {"type": "conductor", "material": "Ag", "specular_reflectance": {"type": "rgb", "value": [0.9, 0.5, 0.25]}},
    {"type": "conductor", "eta": {"type": "rgb", "value": [0.2, 1.1, 2.5]}, "k": {"type": "rgb", "value": [3.0, 0.5, 0.0]}},
    {"type": "conductor", "eta": 1.7, "k": 0.0},
]
COSINES = [1.0, 0.95, 0.8, 0.6, 0.4, 0.2, 0.08, 0.01]
out = []
for case in CASES:
    bsdf = mi.load_dict(case)
    rows = []
    for c in COSINES:
        si = mi.SurfaceInteraction3f()
        si.n = mi.Normal3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(si.n)
        si.wi = mi.Vector3f(math.sqrt(max(0.0, 1 - c * c)), 0, c)
        bs, w = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.5, 0.5))
        rows.append({"cos": c, "weight": [float(w[i]) for i in range(3)]})
    out.append({"bsdf": case, "samples": rows})
path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "conductor-fresnel.json")
with open(path, "w") as f:
    json.dump({"mitsuba": mi.__version__, "variant": "scalar_rgb", "cases": out}, f, indent=1)
print(f"// wrote {path}")
