#!/usr/bin/env python3
"""Mitsuba 3's roughconductor and roughdielectric, as its scalar_rgb variant defines them, for ppm-vk's tests.

Writes rough-bsdfs.json beside this script. For each case (a Mitsuba plugin dict, stored verbatim as "bsdf";
sample_visible left at its default, true) and each incident direction wi (local frame, z = normal; the
incident cosines COSINES at azimuth PHI, so that anisotropy matters; for roughdielectric also the same cosines
from below, light arriving from inside the medium):
  - "eval": the BSDF's value (times |cos_o|, as Mitsuba's eval returns it) and its sampling density (pdf, solid
    angle) at 24 fixed pseudo-random outgoing directions uniform over the whole sphere (random.Random(1), the
    same for every case and wi; "kind": "random"), then at the mirror direction of wi ("kind": "mirror") and,
    for roughdielectric, the specular refraction direction ("kind": "refraction", left out under total
    internal reflection), where the lobes peak. Radiance transport, default BSDFContext.
  - "albedo": the directional albedo, the mean of the weights bsdf.sample returns (f * |cos_o| / pdf, so the
    cosine and Fresnel are in it; invalid samples count as zero) over SAMPLES samples, with "albedo_stderr"
    the standard error of that mean. The random numbers (sample1, sample2) come from numpy's default_rng,
    seeded with [case index, wi index], so the file is deterministic. For roughdielectric also
    "reflect_albedo" / "transmit_albedo" (the same mean, counting only samples whose wo.z has the same /
    opposite sign as wi.z) with their stderrs. In Radiance mode Mitsuba scales transmission by eta_ti^2
    (1/eta^2 entering the denser side), so transmit_albedo exceeds 1 for light leaving it.
    "nonfinite_samples" counts the samples whose weight or wo Mitsuba returned as NaN/inf (counted as zero in
    the means): rare, e.g. 1 of 2^20 for roughdielectric case 1 at wi = (0, 0, -1), where a VNDF sample with
    sample2.y ~ 2e-9 comes back NaN.
At top level: "mitsuba_version", "variant", "samples", "phi", "cosines", and "named_conductors": the RGB eta
and k scalar_rgb uses for each named material (from mi.traverse of a smooth conductor; "none" is Mitsuba's
default, eta 0, k 1, which it treats as a perfect reflector).
ppm-vk's CPU twins of these BSDFs are compared against it.

Run: pip install mitsuba numpy; python3 scenes/references/rough_bsdfs.py   (about 2.5 minutes on two cores)
"""
import json
import math
import os
import random
import time

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

CONDUCTORS = [
    {"type": "roughconductor", "distribution": "ggx", "alpha": 0.2, "material": "Au"},
    {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.3, "material": "Cu"},
    {"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.05, "alpha_v": 0.4,
     "eta": {"type": "rgb", "value": [0.2, 0.9, 1.5]}, "k": {"type": "rgb", "value": [3.9, 2.4, 1.8]},
     "specular_reflectance": {"type": "rgb", "value": [0.9, 0.8, 0.7]}},
    {"type": "roughconductor", "distribution": "beckmann", "alpha_u": 0.5, "alpha_v": 0.15, "material": "Al"},
    {"type": "roughconductor", "distribution": "ggx", "alpha": 0.9},
    {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.02, "material": "Ag"},
]
DIELECTRICS = [
    {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.15, "int_ior": 1.5, "ext_ior": 1.0},
    {"type": "roughdielectric", "distribution": "beckmann", "alpha": 0.4, "int_ior": 1.33, "ext_ior": 1.0,
     "specular_reflectance": 0.9, "specular_transmittance": {"type": "rgb", "value": [0.8, 0.9, 1.0]}},
    {"type": "roughdielectric", "distribution": "ggx", "alpha_u": 0.3, "alpha_v": 0.08, "int_ior": 1.7,
     "ext_ior": 1.2},
]
NAMED = ["Au", "Cu", "Al", "Ag", "none"]
COSINES = [1.0, 0.9, 0.7, 0.5, 0.3, 0.1]
PHI = 0.7
SAMPLES = 1 << 20
N_WO = 24


def rgb(v):
    return [float(v[i]) for i in range(3)]


def vec(v):
    return [float(v[0]), float(v[1]), float(v[2])]


def incident(c):
    s = math.sqrt(max(0.0, 1 - c * c))
    return [s * math.cos(PHI), s * math.sin(PHI), c]


def interaction(wi):
    si = mi.SurfaceInteraction3f()
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    si.wi = mi.Vector3f(*wi)
    return si


def random_directions():
    rng = random.Random(1)
    dirs = []
    for _ in range(N_WO):
        z = 2 * rng.random() - 1
        p = 2 * math.pi * rng.random()
        r = math.sqrt(max(0.0, 1 - z * z))
        dirs.append([r * math.cos(p), r * math.sin(p), z])
    return dirs


def refraction(bsdf_dict, wi):
    """The specular refraction direction of wi (None under total internal reflection)."""
    eta = bsdf_dict["int_ior"] / bsdf_dict["ext_ior"]
    _, cos_t, _, eta_ti = mi.fresnel(wi[2], eta)
    if cos_t == 0 and abs(wi[2]) < 1:  # total internal reflection
        return None
    sin2_t = (1 - wi[2] * wi[2]) * float(eta_ti) ** 2
    if sin2_t >= 1:
        return None
    return vec(mi.refract(mi.Vector3f(*wi), cos_t, eta_ti))


def stats(w):
    """Mean and standard error of the mean of each column of w (float64)."""
    mean = w.mean(axis=0)
    err = w.std(axis=0, ddof=1) / math.sqrt(len(w))
    return [float(x) for x in mean], [float(x) for x in err]


def tabulate(case_index, case, dirs, dielectric):
    bsdf = mi.load_dict(case)
    ctx = mi.BSDFContext()
    wis = [incident(c) for c in COSINES]
    if dielectric:
        wis += [[x, y, -z] for x, y, z in wis]
    rows = []
    for wi_index, wi in enumerate(wis):
        si = interaction(wi)
        evals = []
        targets = [("random", d) for d in dirs] + [("mirror", [-wi[0], -wi[1], wi[2]])]
        if dielectric:
            t = refraction(case, wi)
            if t is not None:
                targets.append(("refraction", t))
        for kind, wo in targets:
            v = mi.Vector3f(*wo)
            evals.append({"kind": kind, "wo": wo, "value": rgb(bsdf.eval(ctx, si, v)),
                          "pdf": float(bsdf.pdf(ctx, si, v))})

        rng = np.random.default_rng([case_index, wi_index])
        u = rng.random((SAMPLES, 3)).tolist()
        w = np.empty((SAMPLES, 4))
        P = mi.Point2f
        for i, (a, b, c) in enumerate(u):
            bs, weight = bsdf.sample(ctx, si, a, P(b, c))
            w[i] = (weight[0], weight[1], weight[2], bs.wo[2])
        bad = ~np.all(np.isfinite(w), axis=1)
        w[bad] = 0.0
        row = {"wi": wi, "eval": evals, "nonfinite_samples": int(bad.sum())}
        row["albedo"], row["albedo_stderr"] = stats(w[:, :3])
        if dielectric:
            same = (w[:, 3] * wi[2]) > 0
            row["reflect_albedo"], row["reflect_albedo_stderr"] = stats(w[:, :3] * same[:, None])
            row["transmit_albedo"], row["transmit_albedo_stderr"] = stats(w[:, :3] * ~same[:, None])
        rows.append(row)
    return {"bsdf": case, "samples": rows}


def named_conductors():
    out = {}
    for name in NAMED:
        p = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
        eta, k = p["eta.value"], p["k.value"]
        as_rgb = lambda v: [float(v)] * 3 if isinstance(v, float) else rgb(v)
        out[name] = {"eta": as_rgb(eta), "k": as_rgb(k)}
    return out


def main():
    start = time.time()
    dirs = random_directions()
    conductors = [tabulate(i, case, dirs, False) for i, case in enumerate(CONDUCTORS)]
    dielectrics = [tabulate(len(CONDUCTORS) + i, case, dirs, True) for i, case in enumerate(DIELECTRICS)]
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "rough-bsdfs.json")
    with open(path, "w") as f:
        json.dump({"mitsuba_version": mi.__version__, "variant": "scalar_rgb", "samples": SAMPLES, "phi": PHI,
                   "cosines": COSINES, "named_conductors": named_conductors(), "roughconductor": conductors,
                   "roughdielectric": dielectrics}, f, indent=1)
    print(f"wrote {path} in {time.time() - start:.0f} s")


# roughplastic_bsdf.py imports the helpers above (the same incidences, outgoing directions and statistics).
if __name__ == "__main__":
    main()
