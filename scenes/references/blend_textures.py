#!/usr/bin/env python3
"""Writes the weight texture of scenes/blend-plane.xml (issue 37) and checks, in Mitsuba 3 itself, the two
facts about `blendbsdf` ppm-vk follows, into scenes/references/blend-weight.json.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 scenes/references/blend_textures.py

scenes/textures/blend-weight.exr (16 x 16, linear RGB, exact in float32): red 0.9 - 0.2 x, green
0.1 + 0.3 y, blue 0.5 + 0.4 sin(2 pi x) (x, y in [0, 1) at pixel centres, y down the image). Its channels
differ on purpose: the weight is their luminance (about 0.31 on average), far from their mean (0.5) or any
one channel, so reading the wrong one shows in the image.

blend-weight.json:
  - "eval_1": Mitsuba's eval_1 of that bitmap (raw, bilinear) at UVS (scalar_rgb), with "rgb" its eval (the
    three channels) at the same points: ppm-vk's test holds eval_1 = luminance(rgb), Mitsuba's
    luminance(c) = 0.212671 r + 0.715160 g + 0.072169 b.
  - "order": a blendbsdf of weight 0 of two diffuse bsdfs, red (0.8, 0.1, 0.1) written first and blue
    (0.1, 0.1, 0.8) second, evaluated at normal incidence and exit (cos 1): its value over cos / pi is the
    reflectance of the component weight 0 selects, the first one written (ppm-vk's `first`).
"""

import json
import os

import numpy as np

import mitsuba as mi

mi.set_variant("scalar_rgb")

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "textures", "blend-weight.exr")
N = 16
x = (np.arange(N) + 0.5) / N
X, Y = np.meshgrid(x, x)  # X along a row (u), Y down the image (v)
rgb = np.stack([0.9 - 0.2 * X, 0.1 + 0.3 * Y, 0.5 + 0.4 * np.sin(2 * np.pi * X)], axis=2).astype(np.float32)
mi.Bitmap(rgb).write(OUT)

tex = mi.load_dict({"type": "bitmap", "filename": OUT, "raw": True})
UVS = [(0.1, 0.2), (0.5, 0.5), (0.73, 0.31), (0.99, 0.01), (0.37, 0.88)]
points = []
for u, v in UVS:
    si = mi.SurfaceInteraction3f()
    si.uv = mi.Point2f(u, v)
    points.append({"uv": [u, v], "eval_1": float(tex.eval_1(si)), "rgb": [float(c) for c in tex.eval(si)]})

blend = mi.load_dict(
    {
        "type": "blendbsdf",
        "weight": 0.0,
        "red": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.1, 0.1]}},
        "blue": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.1, 0.1, 0.8]}},
    }
)
si = mi.SurfaceInteraction3f()
si.n = si.sh_frame.n = mi.Vector3f(0, 0, 1)
si.wi = mi.Vector3f(0, 0, 1)
f = blend.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))
order = [float(c) * np.pi for c in f]

# The XML order too: the scene's own reader, nested bsdfs without names, red first.
xml_blend = mi.load_string(
    """<bsdf version="3.0.0" type="blendbsdf"><float name="weight" value="0"/>
         <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
         <bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.1, 0.8"/></bsdf></bsdf>"""
)
xml_order = [float(c) * np.pi for c in xml_blend.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))]

json.dump(
    {
        "mitsuba_version": mi.__version__,
        "variant": "scalar_rgb",
        "texture": "scenes/textures/blend-weight.exr",
        "eval_1": points,
        "order_dict": order,
        "order_xml": xml_order,
    },
    open(os.path.join(HERE, "blend-weight.json"), "w"),
    indent=1,
)
print("wrote", OUT, "and blend-weight.json:", points[:2], order, xml_order)
