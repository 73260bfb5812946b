#!/usr/bin/env python3
"""Writes the textures of scenes/bump-plane.xml and scenes/mask-pane.xml (issue 37): linear RGB EXR images, exact in float32.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 scenes/references/modifier_textures.py

scenes/textures/bump-height.exr (64 x 64): the height 0.5 + 0.5 sin(2 pi 4 x) sin(2 pi 4 y) (x, y in [0, 1)
across the image), grey. Under `scale` 0.075 on the 2 m plane (dp/du of length 2) its slopes reach
0.075 * 0.5 * 8 pi / 2 = 0.47 (25 degrees).
scenes/textures/bump-normal.exr (64 x 64): the normal (0.4 sin(2 pi 4 x), 0.4 cos(2 pi 3 y), 1)
normalised, stored as (n + 1) / 2 (Mitsuba's normalmap reads 2 c - 1): tilts up to 29 degrees.
"""

import os

import numpy as np

import mitsuba as mi

mi.set_variant("scalar_rgb")

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "textures")
N = 64
# pixel centres
x = (np.arange(N) + 0.5) / N
X, Y = np.meshgrid(x, x)  # X along a row (u), Y down the image (v)

h = 0.5 + 0.5 * np.sin(2 * np.pi * 4 * X) * np.sin(2 * np.pi * 4 * Y)
mi.Bitmap(np.repeat(h[:, :, None], 3, axis=2).astype(np.float32)).write(os.path.join(OUT, "bump-height.exr"))

n = np.stack([0.4 * np.sin(2 * np.pi * 4 * X), 0.4 * np.cos(2 * np.pi * 3 * Y), np.ones_like(X)], axis=2)
n /= np.linalg.norm(n, axis=2, keepdims=True)
mi.Bitmap(((n + 1) / 2).astype(np.float32)).write(os.path.join(OUT, "bump-normal.exr"))
print("wrote", os.path.join(OUT, "bump-height.exr"), "and bump-normal.exr")

# scenes/textures/mask-opacity.png (32 x 32, 8-bit grey, sRGB-encoded as an 8-bit image is read by both
# renderers): the opacity of scenes/mask-pane.xml's pane, round holes of opacity 0 in a sheet whose
# opacity runs from 0.25 to 1 across it (its luminance after sRGB decoding is what Mitsuba's eval_1 gives).
M = 32
xm = (np.arange(M) + 0.5) / M
XM, YM = np.meshgrid(xm, xm)
sheet = 0.25 + 0.75 * XM
holes = ((XM * 4) % 1 - 0.5) ** 2 + ((YM * 4) % 1 - 0.5) ** 2 < 0.3**2
linear = np.where(holes, 0.0, sheet)
encoded = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)
grey = np.round(encoded * 255).astype(np.uint8)
mi.Bitmap(np.repeat(grey[:, :, None], 3, axis=2), pixel_format=mi.Bitmap.PixelFormat.RGB).write(
    os.path.join(OUT, "mask-opacity.png")
)
print("wrote", os.path.join(OUT, "mask-opacity.png"))
