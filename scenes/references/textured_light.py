#!/usr/bin/env python3
"""The radiance texture of scenes/textured-light.xml (issue 37: a texture on an area emitter's `radiance`).

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 scenes/references/textured_light.py

writes scenes/textures/light-radiance.exr, 8 x 8 linear RGB pixels, radiances (not reflectances: above 1):
the left half of the image (columns 0-3) black, the right half (4 + 2 row, 6, 10 - row). Mitsuba's bilinear
filter then ramps between columns 3 and 4; the image's mean, (5.5, 3, 3.25), is the light's mean radiance
over its uv square exactly for this filter with wrap_mode repeat (each pixel's tent integrates to 1/64).
Then make_reference.py renders the scene with Mitsuba 3's path tracer (scenes/references/textured-light.txt).
"""

import os

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "textures")

img = np.zeros((8, 8, 3), dtype=np.float32)
for row in range(8):
    for col in range(4, 8):
        img[row, col] = (4 + 2 * row, 6, 10 - row)
mi.Bitmap(img).write(os.path.join(OUT, "light-radiance.exr"))
print("wrote", os.path.join(OUT, "light-radiance.exr"), "mean", img.reshape(-1, 3).mean(axis=0))
