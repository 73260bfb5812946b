#!/usr/bin/env python3
"""Mitsuba 3's reading of PFM images (src/core/bitmap.cpp, Bitmap::read_pfm), for ppm-vk's PFM reader.

Writes, beside this script:
  textures/rgb.pfm   4 x 3 RGB, written by mi.Bitmap.write (little-endian, scale -1)
  textures/grey.pfm  3 x 2 grey ("Pf"), written by mi.Bitmap.write
  textures/big.pfm   3 x 2 RGB written here big-endian with scale 2 (Mitsuba multiplies by |scale|)
  textures/unit.pfm  3 x 2 RGB in [0, 1] (a reflectance texture), written by mi.Bitmap.write (the seed of
                     tests/hostile_input.rs's mutated images)
  pfm.json           per file: width, height, channels and the pixels Mitsuba's mi.Bitmap reads back
                     (rows from the top, each pixel its channels)
Run: DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 pfm.py
"""
import json
import os
import struct

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
here = os.path.dirname(os.path.abspath(__file__))
os.makedirs(os.path.join(here, "textures"), exist_ok=True)

# Values all different and not a linear function of the position, some above 1 (PFMs hold radiance).
rgb = np.array(
    [[[0.1 * (x + 1) + 0.37 * y * y, 0.05 * x * x + 0.2 * y, 1.7 - 0.13 * x - 0.29 * y] for x in range(4)] for y in range(3)],
    dtype=np.float32,
)
grey = np.array([[[0.25 + 0.5 * x + 0.11 * y * y * y] for x in range(3)] for y in range(2)], dtype=np.float32)
mi.Bitmap(rgb, mi.Bitmap.PixelFormat.RGB).write(os.path.join(here, "textures/rgb.pfm"))
mi.Bitmap(grey, mi.Bitmap.PixelFormat.Y).write(os.path.join(here, "textures/grey.pfm"))
unit = np.array([[[0.1 + 0.3 * x, 0.9 - 0.4 * y, 0.05 * (x + y)] for x in range(3)] for y in range(2)], dtype=np.float32)
mi.Bitmap(unit, mi.Bitmap.PixelFormat.RGB).write(os.path.join(here, "textures/unit.pfm"))

# Big-endian (scale > 0) with scale 2, rows bottom to top as the format stores them.
big = np.array([[[0.5 + x + 3 * y, 0.25 * x, 0.125 * y + 0.01] for x in range(3)] for y in range(2)], dtype=np.float32)
with open(os.path.join(here, "textures/big.pfm"), "wb") as f:
    f.write(b"PF\n3 2\n2.0\n")
    for row in big[::-1]:
        for px in row:
            f.write(struct.pack(">3f", *px))

out = {}
for name in ["rgb.pfm", "grey.pfm", "big.pfm", "unit.pfm"]:
    b = mi.Bitmap(os.path.join(here, "textures", name))
    a = np.array(b)
    if a.ndim == 2:
        a = a[:, :, None]
    out[name] = {
        "width": int(b.width()),
        "height": int(b.height()),
        "channels": int(b.channel_count()),
        "pixels": a.astype(float).tolist(),
    }
# What the script relies on: Mitsuba reads back what it wrote, and multiplies big.pfm by |scale|.
assert np.allclose(np.array(out["rgb.pfm"]["pixels"]), rgb)
assert np.allclose(np.array(out["big.pfm"]["pixels"]), 2 * big)
with open(os.path.join(here, "pfm.json"), "w") as f:
    json.dump({"mitsuba": mi.__version__, "files": out}, f, indent=1)
print("wrote", list(out))
