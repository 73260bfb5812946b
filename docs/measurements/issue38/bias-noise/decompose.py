"""relMSE of two renders of one scene split into noise and bias^2 (run.sh beside this file).

x1, x2: two renders with different seeds; r: the reference, with its own noise (NAME_var.exr beside it)
removed as docs/report-format.md does. Noise per run: mean((x1 - x2)^2 / 2) / (r^2 + 0.01); bias^2: the
mean's error less half of that. Regions: the whole image and the torus box (x 80, y 110, 96 x 40).
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")


def load(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


name, p1, p2, pref = sys.argv[1:5]
x1, x2, r = load(p1), load(p2), load(pref)
v = load(pref.replace(".exr", "_var.exr"))
w = 1.0 / (r * r + 0.01)
for region, sl in [("whole", np.s_[:, :]), ("torus", np.s_[110:150, 80:176])]:
    e1 = np.mean((((x1 - r) ** 2 - v) * w)[sl])
    e2 = np.mean((((x2 - r) ** 2 - v) * w)[sl])
    noise = np.mean(((x1 - x2) ** 2 / 2 * w)[sl])
    mean_err = np.mean(((((x1 + x2) / 2 - r) ** 2 - v) * w)[sl])
    bias2 = mean_err - noise / 2
    print(f"{name} {region}: relMSE {e1:.5f} and {e2:.5f}; noise {noise:.5f}, bias^2 {bias2:.5f} "
          f"({bias2 / ((e1 + e2) / 2):.0%} of the error)")
