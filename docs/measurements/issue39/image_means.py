#!/usr/bin/env python3
"""Each EXR's mean RGB, and each channel's ratio to the first file's (issue 39: the interior's image mean
against Mitsuba's, a sanity check of a speed scene).

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        python3 docs/measurements/issue39/image_means.py scenes/references/interior.exr interior-160.exr
"""
import sys

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
first = None
for path in sys.argv[1:]:
    mean = np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)).reshape(-1, 3).mean(0)
    first = mean if first is None else first
    print(f"{path}: mean {np.round(mean, 5).tolist()}, ratio to the first {np.round(mean / first, 4).tolist()}")
