#!/usr/bin/env python3
"""Mitsuba 3's roughplastic, as its scalar_rgb variant defines it, for ppm-vk's tests.

Writes roughplastic-bsdf.json beside this script. For each case (a Mitsuba plugin dict, stored verbatim as
"bsdf"; sample_visible left at its default, true) and each incident direction wi (local frame, z = normal;
the incident cosines COSINES at azimuth PHI, upper hemisphere only: roughplastic is one-sided):
  - "eval": the BSDF's value (times cos_o, as Mitsuba's eval returns it) and its sampling density (pdf, solid
    angle) at the same 24 fixed pseudo-random outgoing directions as rough_bsdfs.py (uniform over the whole
    sphere, random.Random(1), the same for every case and wi; "kind": "random"; those below the surface give
    zero and are kept), then at the mirror direction of wi ("kind": "mirror"), where the coat's lobe peaks.
    Each entry also has "specular_value": the value of the same roughplastic with diffuse_reflectance 0 (the
    specular coat lobe alone: the coat's value does not depend on diffuse_reflectance), so that
    value - specular_value is the diffuse part alone. Radiance transport, default BSDFContext.
  - "albedo": the directional albedo, the mean of the weights bsdf.sample returns (f * cos_o / pdf; invalid
    samples count as zero) over SAMPLES samples, with "albedo_stderr" the standard error of that mean. The
    random numbers (sample1, sample2) come from numpy's default_rng, seeded with [case index, wi index], so
    the file is deterministic. "nonfinite_samples" counts samples whose weight or wo came back NaN/inf
    (counted as zero).
Per case also "diffuse_directional": the diffuse part (value - specular_value) at wo = (0, 0, 1) (cos_o = 1,
so no division is needed) for incident cosines mu = k/32, k = 0..32 (1e-4 in place of 0), wi at azimuth PHI.
Mitsuba's diffuse part is diffuse / (1 - F_int) / pi / eta^2 * cos_o * T(mu_i) * T(mu_o), with T its table
of the coat's external transmittance (1 minus the rough coat's directional albedo, MI_ROUGH_TRANSMITTANCE_RES
points, linearly interpolated), so this row is T(mu) up to a constant factor (the same for every mu).
At top level: "mitsuba_version", "variant", "samples", "phi", "cosines", "directional_mu", "directional_wo".
ppm-vk's CPU twin of this BSDF is compared against it.

Run: pip install mitsuba numpy; python3 scenes/references/roughplastic_bsdf.py
"""
import json
import os
import time

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

# The incidences, the 24 outgoing directions and the statistics of rough_bsdfs.py, beside this script.
from rough_bsdfs import COSINES, PHI, SAMPLES, incident, interaction, random_directions, rgb, stats  # noqa: E402

CASES = [
    {"type": "roughplastic"},
    {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3, "int_ior": 1.5,
     "diffuse_reflectance": {"type": "rgb", "value": [0.7, 0.1, 0.05]}, "nonlinear": True},
    {"type": "roughplastic", "distribution": "beckmann", "alpha": 0.05, "int_ior": 1.9, "ext_ior": 1.333,
     "diffuse_reflectance": {"type": "rgb", "value": [0.2, 0.5, 0.8]}, "specular_reflectance": 0.8},
    {"type": "roughplastic", "distribution": "ggx", "alpha": 0.6, "diffuse_reflectance": 0.9},
]
DIRECTIONAL_MU = [max(k / 32, 1e-4) for k in range(33)]
DIRECTIONAL_WO = [0.0, 0.0, 1.0]


def coat_only(case):
    """The same plugin with diffuse_reflectance 0: the specular coat lobe alone."""
    d = dict(case)
    d["diffuse_reflectance"] = 0.0
    return d


def tabulate(case_index, case, dirs):
    bsdf = mi.load_dict(case)
    coat = mi.load_dict(coat_only(case))
    ctx = mi.BSDFContext()
    rows = []
    for wi_index, wi in enumerate(incident(c) for c in COSINES):
        si = interaction(wi)
        evals = []
        targets = [("random", d) for d in dirs] + [("mirror", [-wi[0], -wi[1], wi[2]])]
        for kind, wo in targets:
            v = mi.Vector3f(*wo)
            evals.append({"kind": kind, "wo": wo, "value": rgb(bsdf.eval(ctx, si, v)),
                          "pdf": float(bsdf.pdf(ctx, si, v)), "specular_value": rgb(coat.eval(ctx, si, v))})

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
        rows.append(row)
        print(f"case {case_index} cos {COSINES[wi_index]}: albedo {row['albedo']}", flush=True)

    directional = []
    v = mi.Vector3f(*DIRECTIONAL_WO)
    for mu in DIRECTIONAL_MU:
        wi = incident(mu)
        si = interaction(wi)
        full, spec = rgb(bsdf.eval(ctx, si, v)), rgb(coat.eval(ctx, si, v))
        directional.append({"mu": mu, "wi": wi, "value": [f - s for f, s in zip(full, spec)]})
    return {"bsdf": case, "samples": rows, "diffuse_directional": directional}


start = time.time()
dirs = random_directions()
cases = [tabulate(i, case, dirs) for i, case in enumerate(CASES)]
path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "roughplastic-bsdf.json")
with open(path, "w") as f:
    json.dump({"mitsuba_version": mi.__version__, "variant": "scalar_rgb", "samples": SAMPLES, "phi": PHI,
               "cosines": COSINES, "directional_mu": DIRECTIONAL_MU, "directional_wo": DIRECTIONAL_WO,
               "roughplastic": cases}, f, indent=1)
print(f"wrote {path} in {time.time() - start:.0f} s")
