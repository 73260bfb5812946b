#!/usr/bin/env python3
"""Writes scenes/textures/sky.exr, the environment map of scenes/env-window.xml (issue 36).

    python3 scenes/references/make_sky.py

A 256 x 128 latitude-longitude map in linear RGB, as Mitsuba 3's `envmap` reads it: row 0 is the zenith
(+y), the last row the nadir, and the column of pixel centre u (0..1) holds the directions of azimuth
phi = 2 pi u measured from -z towards +x (Mitsuba's uv = (atan2(x, -z) / 2 pi, acos(y) / pi)). A sky
gradient from a blue zenith to a pale horizon, a grey ground below the horizon, and a small sun: a
Gaussian blob of about 1.5 texels' width, centred on the direction SUN (towards the sun), whose total
irradiance on a plane facing it is about SUN_E. Prints what a test can check: the sun's direction and
irradiance, and the whole map's irradiance on an upward-facing plane (by the same texel sums, each
texel's solid angle exact).
"""

import os

import numpy as np

import mitsuba as mi

mi.set_variant("scalar_rgb")

HERE = os.path.dirname(os.path.abspath(__file__))
W, H = 256, 128
SUN = np.array([0.3, 0.6, -0.75])  # towards the sun: above the horizon, behind the room's window (-z)
SUN_E = 8.0  # the sun's irradiance (W/m^2 per channel, white) on a plane facing it
SUN_SIGMA = 0.02  # radians: the blob's Gaussian width (2 pi / 256 = 0.0245 per texel)


def directions():
    """Unit directions of the texel centres, and each texel's solid angle."""
    u = (np.arange(W) + 0.5) / W
    v = (np.arange(H) + 0.5) / H
    phi = 2 * np.pi * u[None, :]
    theta = np.pi * v[:, None]
    d = np.stack(np.broadcast_arrays(np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)), -1)
    edges = np.pi * np.arange(H + 1) / H
    omega = (2 * np.pi / W) * (np.cos(edges[:-1]) - np.cos(edges[1:]))
    return d, np.broadcast_to(omega[:, None], (H, W))


def main():
    d, omega = directions()
    y = d[..., 1]
    t = np.clip(y, 0, 1) ** 0.5
    zenith, horizon, ground = np.array([0.25, 0.45, 0.9]), np.array([0.9, 0.95, 1.0]), np.array([0.25, 0.22, 0.2])
    sky = np.where(y[..., None] > 0, horizon + (zenith - horizon) * t[..., None], ground)
    sun = SUN / np.linalg.norm(SUN)
    ang = np.arccos(np.clip(d @ sun, -1, 1))
    blob = np.exp(-0.5 * (ang / SUN_SIGMA) ** 2)
    # scale the blob so that its irradiance on a plane facing the sun is SUN_E
    k = SUN_E / np.sum(blob * omega * np.clip(d @ sun, 0, None))
    img = (sky + (k * blob)[..., None]).astype(np.float32)
    out = os.path.join(HERE, "..", "textures", "sky.exr")
    mi.Bitmap(img).write(out)
    e_sun = np.sum((k * blob * omega * np.clip(d @ sun, 0, None)))
    e_up = np.sum(img * (omega * np.clip(y, 0, None))[..., None], axis=(0, 1))
    e_up_sky = np.sum(sky * (omega * np.clip(y, 0, None))[..., None], axis=(0, 1))
    print(f"wrote {os.path.normpath(out)}: {W}x{H}, peak {img.max():.1f}")
    print(f"sun towards ({sun[0]:.4f}, {sun[1]:.4f}, {sun[2]:.4f}), irradiance facing it {e_sun:.4f} per channel, "
          f"on a horizontal plane {e_sun * sun[1]:.4f} (the blob's texels, as sampled)")
    print(f"whole map on an upward plane (open sky, no walls): E = {e_up}, of which the sky without the sun {e_up_sky}")


if __name__ == "__main__":
    main()
