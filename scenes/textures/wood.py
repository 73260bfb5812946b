#!/usr/bin/env python3
"""Writes wood.png beside this script: a procedural wood grain (rings of a log cut along its length, with a
few waves in them, tiling without a seam), 512 x 256 pixels, 8-bit sRGB, for scenes/gold-ring.toml's varnished table. Python's
standard library only (zlib for the PNG); the same file every run.

Run: python3 scenes/textures/wood.py
"""
import math
import os
import struct
import zlib

W, H = 512, 256
LIGHT = (0.50, 0.33, 0.18)  # linear RGB of the light wood between the rings
DARK = (0.32, 0.19, 0.09)   # and of the dark late wood of a ring


def srgb(x):
    x = min(max(x, 0.0), 1.0)
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055


def pixel(x, y):
    u, v = x / W, y / H
    # Distance from the log's axis, which runs along u, bent by a few slow waves: the rings' pattern. Every
    # term has a whole number of periods across the image, so it tiles without a seam.
    wave = 0.035 * math.sin(2 * math.pi * (u + 0.2)) + 0.02 * math.sin(2 * math.pi * (3 * u + v))
    r = 0.5 - 0.5 * math.cos(2 * math.pi * (v + wave)) + 0.03 * math.sin(2 * math.pi * 5 * u)
    t = (r * 4.0) % 1.0
    late = t ** 3  # the dark band at each ring's end
    fibre = 0.05 * math.sin(2 * math.pi * (23.0 * v + 3.0 * math.sin(2 * math.pi * 2.0 * u)))
    mix = min(max(late + fibre, 0.0), 1.0)
    return tuple(round(255 * srgb(a + (b - a) * mix)) for a, b in zip(LIGHT, DARK))


def main():
    rows = b"".join(b"\x00" + bytes(c for x in range(W) for c in pixel(x, y)) for y in range(H))
    chunk = lambda kind, data: struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "wood.png")
    with open(path, "wb") as f:
        f.write(png)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
