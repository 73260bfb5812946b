"""Splits relMSE against a reference into its variance across seeds and the squared bias of their mean
(the reference's own noise removed), per region: the seeds' images must be renders of one scene that
differ only in --seed. Also prints the share of each seed's region error in its worst 1% of pixels (each
pixel's error less the reference's variance there, at least 0).
Usage: python3 bias_variance.py REF.exr REF_var.exr "{'name': (x0, y0, x1, y1), ...}" SEED0.exr SEED1.exr ...
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")


def load(p):
    return np.array(mi.Bitmap(p).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32), dtype=np.float64)


ref, var, boxes = load(sys.argv[1]), load(sys.argv[2]), eval(sys.argv[3])
imgs = [load(p) for p in sys.argv[4:]]
for name, (x0, y0, x1, y1) in boxes.items():
    R, V = ref[y0:y1, x0:x1], var[y0:y1, x0:x1]
    w = 1 / (R**2 + 0.01)
    I = [i[y0:y1, x0:x1] for i in imgs]
    rel = [(((i - R) ** 2 - V) * w).mean() for i in I]
    m, sv, n = np.mean(I, axis=0), np.var(I, axis=0, ddof=1), len(I)
    bias2 = (((m - R) ** 2 - V - sv / n) * w).mean()
    tops = []
    for i in I:
        e = np.sort(np.maximum(((i - R) ** 2 - V) * w, 0.0).mean(axis=2).ravel())[::-1]
        tops.append(e[: len(e) // 100].sum() / e.sum())
    print(f"{name}: relMSE per seed {' '.join(f'{r:.5f}' for r in rel)}; variance {(sv * w).mean():.5f}, "
          f"bias^2 {bias2:.5f}; mean / reference {m.mean() / R.mean():.4f}; "
          f"worst 1% of pixels' share {' '.join(f'{t:.2f}' for t in tops)}")
