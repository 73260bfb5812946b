#!/usr/bin/env python3
"""Mitsuba 3's plastic and thindielectric, as its RGB variants define them, for ppm-vk's tests.

Writes coated-bsdfs.json beside this script: for each plastic case, at several incident cosines, the
specular lobe's weight (specular_reflectance times the coat's Fresnel term: the sampled weight times its
probability), the BSDF's value (times the outgoing cosine, as Mitsuba's eval returns it) at several outgoing
cosines, and the directional albedo of the diffuse lobe (eval integrated over the hemisphere: it does not
depend on the azimuth, so a midpoint rule over the outgoing cosine with 4096 points); for each thin
dielectric case the probability of reflection (Fresnel with its internal reflections) and both weights.
ppm-vk's tests compare against it (crates/reference/src/plastic.rs, crates/materials/src/plastic.rs and
thin_dielectric.rs).

Run: pip install mitsuba numpy; python3 scenes/references/coated_bsdfs.py
"""
import json
import math
import os

import mitsuba as mi

mi.set_variant("scalar_rgb")

PLASTICS = [
    {"type": "plastic"},
    {"type": "plastic", "diffuse_reflectance": {"type": "rgb", "value": [0.3, 0.5, 0.8]}, "int_ior": 1.5,
     "specular_reflectance": 0.8, "nonlinear": True},
    {"type": "plastic", "diffuse_reflectance": {"type": "rgb", "value": [0.9, 0.1, 0.05]}, "int_ior": 1.9,
     "ext_ior": 1.333},
    {"type": "plastic", "diffuse_reflectance": 0.2, "int_ior": 1.3, "nonlinear": True},
]
THINS = [
    {"type": "thindielectric"},
    {"type": "thindielectric", "int_ior": 1.5, "specular_transmittance": {"type": "rgb", "value": [0.95, 0.75, 0.5]}},
    {"type": "thindielectric", "int_ior": 2.4, "ext_ior": 1.333, "specular_reflectance": 0.5},
]
COSINES = [1.0, 0.9, 0.7, 0.5, 0.3, 0.15, 0.05]
N = 4096


def interaction(c):
    si = mi.SurfaceInteraction3f()
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    si.wi = mi.Vector3f(math.sqrt(max(0.0, 1 - c * c)), 0, c)
    return si


def rgb(v):
    return [float(v[i]) for i in range(3)]


def direction(c):
    return mi.Vector3f(-math.sqrt(max(0.0, 1 - c * c)), 0, c)


plastics = []
for case in PLASTICS:
    bsdf = mi.load_dict(case)
    rows = []
    for c in COSINES:
        si = interaction(c)
        bs, w = bsdf.sample(mi.BSDFContext(), si, 0.0, mi.Point2f(0.5, 0.5))
        specular = [x * float(bs.pdf) for x in rgb(w)]
        evals = [{"cos_o": co, "value": rgb(bsdf.eval(mi.BSDFContext(), si, direction(co)))} for co in COSINES]
        albedo = [0.0, 0.0, 0.0]
        for k in range(N):
            mu = (k + 0.5) / N
            v = rgb(bsdf.eval(mi.BSDFContext(), si, direction(mu)))
            albedo = [a + 2 * math.pi * x / N for a, x in zip(albedo, v)]
        rows.append({"cos": c, "specular": specular, "eval": evals, "diffuse_albedo": albedo})
    plastics.append({"bsdf": case, "samples": rows})

thins = []
for case in THINS:
    bsdf = mi.load_dict(case)
    rows = []
    for c in COSINES:
        si = interaction(c)
        bs_r, w_r = bsdf.sample(mi.BSDFContext(), si, 0.0, mi.Point2f(0.5, 0.5))
        bs_t, w_t = bsdf.sample(mi.BSDFContext(), si, 0.999999, mi.Point2f(0.5, 0.5))
        rows.append({"cos": c, "reflect_prob": float(bs_r.pdf), "reflect_weight": rgb(w_r),
                     "transmit_weight": rgb(w_t)})
    thins.append({"bsdf": case, "samples": rows})

fdr = [{"eta": e, "fdr": float(mi.fresnel_diffuse_reflectance(e))} for e in [0.5, 0.67, 0.9, 1.1, 1.49, 2.0, 3.0]]
path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "coated-bsdfs.json")
with open(path, "w") as f:
    json.dump({"mitsuba": mi.__version__, "variant": "scalar_rgb", "plastic": plastics, "thindielectric": thins,
               "fresnel_diffuse_reflectance": fdr}, f, indent=1)
print(f"wrote {path}")
