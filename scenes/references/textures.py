#!/usr/bin/env python3
"""Mitsuba 3's bitmap and checkerboard textures and its shapes' texture coordinates, for ppm-vk's tests.

Writes, beside this script:
  textures/tiles.png     64 x 48 8-bit sRGB RGB test image: coloured tiles 8 px wide (palette index
                         (tile column + 2 tile row) mod 8, times 0.8) plus a horizontal ramp on R and a
                         vertical ramp on G (0..51); pixel (0, 0) is black, the image has no symmetry
  textures/gradient.exr  5 x 3 float32 RGB EXR, linear values in [0.05, 0.95], all 45 different and not
                         a linear function of the position (so a misplaced filter footprint shows)
  textures/gray.png      7 x 5 8-bit sRGB single-channel (grayscale) PNG
  textures/quad.obj      two triangles with `vt` (for shape_uv's OBJ case)
  textures/box.obj       the 0.3 m textured box of cornell-textured.xml: 12 triangles, CCW seen from
                         outside, each face with vt (0,0) (1,0) (1,1) (0,1) at its corners (bottom-left,
                         bottom-right, top-right, top-left seen from outside; for the top face "bottom"
                         is +z, for the bottom face it is -z)
  textures.json          what Mitsuba's scalar_rgb variant returns:
    "cases": per texture case, the texture's parameters as given to mi.load_dict ("params", to_uv as a list
      of operations applied in order), "to_uv": the 2x3 affine matrix [a, b, c, d, e, f] that Mitsuba uses
      (u' = a u + b v + c, v' = d u + e v + f; the 4x4 to_uv's rows 0-1 and columns 0, 1, 3), "size"
      [width, height] for bitmaps, and "samples": {"uv", "value" (tex.eval, linear RGB), and "edge": true
      where the value jumps within 1e-5 of uv (nearest-filter pixel edges, checker edges: a different
      rounding may land on the other side)}
    "tiles_pixels": for some pixels (x, y) of tiles.png (y = row from the top), the 8-bit sRGB values,
      Mitsuba's linear values (bitmap, raw false, nearest, evaluated at the pixel centre) and its raw values
      (raw true: value / 255)
    "gray_pixels": the same for gray.png
    "shape_uv": ray hits on rectangle (with and without to_world), sphere and an OBJ mesh: ray origin and
      direction, hit point p and the si.uv Mitsuba reports
    "notes": conventions observed (checked by asserts below)

Run: pip install mitsuba numpy; python3 scenes/references/textures.py
"""
import json
import math
import os
import re

import numpy as np

import mitsuba as mi

mi.set_variant("scalar_rgb")

HERE = os.path.dirname(os.path.abspath(__file__))
TEX = os.path.join(HERE, "textures")


# ---------------------------------------------------------------------------------------------------------
# Test images and meshes
# ---------------------------------------------------------------------------------------------------------

PALETTE = np.array([
    [0, 0, 0], [255, 255, 255], [230, 40, 20], [20, 200, 60],
    [30, 60, 240], [250, 210, 10], [140, 20, 180], [10, 170, 190],
], dtype=np.float64)


def tiles_image():
    h, w = 48, 64
    img = np.zeros((h, w, 3), dtype=np.float64)
    for y in range(h):
        for x in range(w):
            c = PALETTE[(x // 8 + 2 * (y // 8)) % 8] * 0.8
            c[0] += 51.0 * x / (w - 1)
            c[1] += 51.0 * y / (h - 1)
            img[y, x] = c
    img = np.clip(np.round(img), 0, 255).astype(np.uint8)
    assert img.min() == 0 and img.max() == 255
    return img


def gradient_image():
    h, w = 3, 5
    n = h * w * 3
    idx = (np.arange(n) * 17) % n  # a permutation (gcd(17, 45) = 1)
    return (0.05 + 0.9 * idx / (n - 1)).reshape(h, w, 3).astype(np.float32)


def gray_image():
    h, w = 5, 7
    y, x = np.mgrid[0:h, 0:w]
    return ((x * 37 + y * 53 + 11 + (x * y) * 13) % 256).astype(np.uint8)


def png_header(path):
    """(width, height, bit depth, colour type) from a PNG's IHDR."""
    b = open(path, "rb").read(33)
    assert b[:8] == b"\x89PNG\r\n\x1a\n" and b[12:16] == b"IHDR"
    return int.from_bytes(b[16:20], "big"), int.from_bytes(b[20:24], "big"), b[24], b[25]


def write_images():
    os.makedirs(TEX, exist_ok=True)
    tiles = tiles_image()
    mi.Bitmap(tiles).write(os.path.join(TEX, "tiles.png"))
    assert png_header(os.path.join(TEX, "tiles.png")) == (64, 48, 8, 2)  # 8-bit RGB
    mi.Bitmap(gradient_image()).write(os.path.join(TEX, "gradient.exr"))
    gray = gray_image()
    mi.Bitmap(gray).write(os.path.join(TEX, "gray.png"))
    assert png_header(os.path.join(TEX, "gray.png")) == (7, 5, 8, 0)  # 8-bit grayscale
    # read back: exactly what was written
    assert np.array_equal(np.array(mi.Bitmap(os.path.join(TEX, "tiles.png"))), tiles)
    assert np.array_equal(np.array(mi.Bitmap(os.path.join(TEX, "gray.png"))).reshape(gray.shape), gray)
    assert np.array_equal(np.array(mi.Bitmap(os.path.join(TEX, "gradient.exr"))), gradient_image())
    return tiles, gray


QUAD_V = [(-0.6, -0.4, 0.1), (0.8, -0.5, 0.0), (0.7, 0.6, -0.1), (-0.5, 0.5, 0.0)]
QUAD_VT = [(0.1, 0.2), (0.9, 0.1), (0.8, 0.7), (0.2, 0.9)]


def write_quad_obj():
    with open(os.path.join(TEX, "quad.obj"), "w") as f:
        f.write("# two triangles with texture coordinates, written by textures.py\n")
        for v in QUAD_V:
            f.write("v %g %g %g\n" % v)
        for vt in QUAD_VT:
            f.write("vt %g %g\n" % vt)
        f.write("f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")


BOX_MIN = (-0.7, 0.0, 0.3)
BOX_SIZE = 0.3


def write_box_obj():
    x0, y0, z0 = BOX_MIN
    x1, y1, z1 = x0 + BOX_SIZE, y0 + BOX_SIZE, z0 + BOX_SIZE
    # each face: corners bottom-left, bottom-right, top-right, top-left seen from outside (CCW)
    faces = [
        ("+z", [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]),
        ("-z", [(x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)]),
        ("+x", [(x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)]),
        ("-x", [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)]),
        ("+y", [(x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (x0, y1, z0)]),
        ("-y", [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)]),
    ]
    normals = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1),
               "-z": (0, 0, -1)}
    with open(os.path.join(TEX, "box.obj"), "w") as f:
        f.write("# cornell-textured.xml's box: %g m cube, x %g..%g, y %g..%g, z %g..%g; written by textures.py\n"
                "# 12 triangles, CCW seen from outside; each face shows the whole image upright\n"
                % (BOX_SIZE, x0, x1, y0, y1, z0, z1))
        f.write("o box\n")
        for _, corners in faces:
            for c in corners:
                f.write("v %.6g %.6g %.6g\n" % c)
        for vt in [(0, 0), (1, 0), (1, 1), (0, 1)]:
            f.write("vt %g %g\n" % vt)
        for k, (name, corners) in enumerate(faces):
            # check the winding: (c1 - c0) x (c2 - c0) is the outward normal
            a, b, c = (np.array(p) for p in corners[:3])
            n = np.cross(b - a, c - a)
            assert np.allclose(n / np.linalg.norm(n), normals[name]), name
            i = 4 * k + 1
            f.write("f %d/1 %d/2 %d/3\n" % (i, i + 1, i + 2))
            f.write("f %d/1 %d/3 %d/4\n" % (i, i + 2, i + 3))


# ---------------------------------------------------------------------------------------------------------
# Textures
# ---------------------------------------------------------------------------------------------------------

def transform(ops):
    """to_uv from operations applied in order: [{"scale": [sx, sy]}, {"rotate": deg}, {"translate": [tx, ty]}]."""
    t = mi.ScalarTransform4f()
    for op in ops:
        (k, v), = op.items()
        if k == "scale":
            t = mi.ScalarTransform4f().scale([v[0], v[1], 1]) @ t
        elif k == "translate":
            t = mi.ScalarTransform4f().translate([v[0], v[1], 0]) @ t
        elif k == "rotate":  # about the z axis, counter-clockwise in (u, v)
            t = mi.ScalarTransform4f().rotate([0, 0, 1], v) @ t
        else:
            raise ValueError(k)
    return t


def ops_matrix(ops):
    """The same transform as transform(ops), as a 3x3 numpy matrix computed here (independent check)."""
    m = np.eye(3)
    for op in ops:
        (k, v), = op.items()
        if k == "scale":
            s = np.diag([v[0], v[1], 1.0])
        elif k == "translate":
            s = np.array([[1, 0, v[0]], [0, 1, v[1]], [0, 0, 1.0]])
        else:
            c, sn = math.cos(math.radians(v)), math.sin(math.radians(v))
            s = np.array([[c, -sn, 0], [sn, c, 0], [0, 0, 1.0]])
        m = s @ m
    return m


def rgb(v):
    return [float(v[i]) for i in range(3)]


def ev(tex, u, v):
    si = mi.SurfaceInteraction3f()
    si.uv = mi.Point2f(u, v)
    return rgb(tex.eval(si))


def uv_points(w, h):
    """About 25 points: corners, pixel centres, pixel edges, between centres, outside [0, 1], random."""
    pts = [
        (0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (1.0, 0.0), (0.5, 0.5),
        # pixel centres
        (0.5 / w, 0.5 / h), ((w - 0.5) / w, (h - 0.5) / h), (2.5 / w, 1.5 / h), ((w // 2 + 0.5) / w, (h - 1.5) / h),
        # pixel edges and between centres
        (1.0 / w, 1.0 / h), (3.0 / w, 0.5 / h), (1.25 / w, 2.75 / h), ((w - 0.2) / w, 0.3 / h),
        (0.1 / w, (h - 0.1) / h),
        # outside [0, 1]
        (-1.3, 2.7), (2.7, -1.3), (-0.2, 0.3), (1.2, 0.6), (0.3, -0.05), (0.7, 1.05), (-0.01, -0.01),
        (1.01, 1.01), (-2.0, 3.0), (1.0 + 0.5 / w, -0.5 / h),
    ]
    rng = np.random.default_rng(7)
    pts += [tuple(float(x) for x in rng.uniform(-1.5, 2.5, 2)) for _ in range(3)]
    pts += [tuple(float(x) for x in rng.uniform(0.0, 1.0, 2)) for _ in range(3)]
    return [(float(np.float32(u)), float(np.float32(v))) for u, v in pts]


def sample_case(tex, pts):
    out = []
    for u, v in pts:
        val = ev(tex, u, v)
        d = 1e-5
        near = [ev(tex, u + du, v + dv) for du, dv in [(d, 0), (-d, 0), (0, d), (0, -d)]]
        edge = any(max(abs(a - b) for a, b in zip(val, n)) > 1e-3 for n in near)
        s = {"uv": [u, v], "value": val}
        if edge:
            s["edge"] = True
        out.append(s)
    return out


def load(params, to_uv_ops):
    d = dict(params)
    if d["type"] == "bitmap":
        d["filename"] = os.path.join(HERE, params["filename"])
    for k in ("color0", "color1"):
        if isinstance(d.get(k), list):
            d[k] = {"type": "rgb", "value": d[k]}
    if to_uv_ops:
        d["to_uv"] = transform(to_uv_ops)
    return mi.load_dict(d)


def affine(tex):
    m = mi.traverse(tex)["to_uv"].matrix
    return [float(m[0][0]), float(m[0][1]), float(m[0][2]), float(m[1][0]), float(m[1][1]), float(m[1][2])]


SIZES = {"textures/tiles.png": (64, 48), "textures/gradient.exr": (5, 3), "textures/gray.png": (7, 5)}

SCALE_TRANSLATE = [{"scale": [2, 3]}, {"translate": [0.1, -0.2]}]
ROTATE = [{"scale": [1.5, 0.8]}, {"rotate": 30}, {"translate": [0.25, 0.4]}]


def bitmap(filename, filt, wrap, raw=False):
    return {"type": "bitmap", "filename": filename, "filter_type": filt, "wrap_mode": wrap, "raw": raw}


CASES = []
for filt in ("bilinear", "nearest"):
    for wrap in ("repeat", "mirror", "clamp"):
        CASES.append((bitmap("textures/tiles.png", filt, wrap), []))
CASES += [
    (bitmap("textures/tiles.png", "bilinear", "repeat", raw=True), []),
    (bitmap("textures/tiles.png", "nearest", "mirror", raw=True), []),
    (bitmap("textures/tiles.png", "bilinear", "repeat"), SCALE_TRANSLATE),
    (bitmap("textures/tiles.png", "nearest", "mirror"), ROTATE),
    (bitmap("textures/tiles.png", "bilinear", "clamp"), ROTATE),
]
for filt in ("bilinear", "nearest"):
    for wrap in ("repeat", "mirror", "clamp"):
        CASES.append((bitmap("textures/gradient.exr", filt, wrap), []))
CASES += [
    (bitmap("textures/gradient.exr", "bilinear", "mirror"), SCALE_TRANSLATE),
    (bitmap("textures/gray.png", "bilinear", "repeat"), []),
    (bitmap("textures/gray.png", "nearest", "clamp"), []),
    (bitmap("textures/gray.png", "bilinear", "mirror", raw=True), []),
    (bitmap("textures/gray.png", "bilinear", "repeat"), ROTATE),
    ({"type": "checkerboard"}, []),
    ({"type": "checkerboard", "color0": [0.9, 0.5, 0.1], "color1": [0.05, 0.3, 0.7]}, [{"scale": [4, 4]}]),
    ({"type": "checkerboard", "color0": [0.9, 0.5, 0.1], "color1": [0.05, 0.3, 0.7]}, ROTATE),
]


def srgb_to_linear(c):
    c = np.asarray(c, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def texture_cases():
    cases = []
    for params, ops in CASES:
        tex = load(params, ops)
        w, h = SIZES.get(params.get("filename"), (8, 8))
        pts = uv_points(w, h)
        if params["type"] == "checkerboard":
            pts += [(0.125, 0.375), (0.25, 0.75), (0.5, 0.25), (0.75, 0.5)]  # exactly on checker edges
        m = affine(tex)
        assert np.allclose(np.array(m).reshape(2, 3), ops_matrix(ops)[:2], atol=1e-6), (m, ops)
        # the 2x3 matrix reproduces to_uv: tex(uv) == tex without to_uv at (a u + b v + c, d u + e v + f)
        plain = load(params, [])
        for u, v in pts:
            u2, v2 = m[0] * u + m[1] * v + m[2], m[3] * u + m[4] * v + m[5]
            a, b = ev(tex, u, v), ev(plain, u2, v2)
            if params.get("filter_type") == "bilinear":
                assert np.allclose(a, b, atol=1e-4), (params, ops, u, v, a, b)
        samples = sample_case(tex, pts)
        if params.get("filter_type") == "nearest" or params["type"] == "checkerboard":
            for (u, v), s in zip(pts, samples):
                u2, v2 = m[0] * u + m[1] * v + m[2], m[3] * u + m[4] * v + m[5]
                if not s.get("edge"):
                    assert np.allclose(s["value"], ev(plain, u2, v2), atol=1e-5), (params, ops, u, v)
        case = {"params": params, "to_uv_ops": ops, "to_uv": m}
        if params["type"] == "bitmap":
            case["size"] = [w, h]
        case["samples"] = samples
        cases.append(case)
    return cases


def pixel_values(filename, img, pixels):
    w, h = img.shape[1], img.shape[0]
    lin = load(bitmap(filename, "nearest", "clamp"), [])
    raw = load(bitmap(filename, "nearest", "clamp", raw=True), [])
    out = []
    for x, y in pixels:
        uv = ((x + 0.5) / w, (y + 0.5) / h)
        s8 = img[y, x].tolist() if img.ndim == 3 else [int(img[y, x])]
        lv, rv = ev(lin, *uv), ev(raw, *uv)
        exp = srgb_to_linear(s8 if len(s8) == 3 else s8 * 3)
        assert np.allclose(lv, exp, atol=2e-6), (x, y, lv, exp)
        assert np.allclose(rv, np.array(s8 if len(s8) == 3 else s8 * 3) / 255.0, atol=1e-6)
        out.append({"xy": [x, y], "uv": list(uv), "srgb8": s8, "linear": lv, "raw": rv})
    return out


# ---------------------------------------------------------------------------------------------------------
# Texture coordinates on shapes
# ---------------------------------------------------------------------------------------------------------

def hit(scene, o, d):
    ray = mi.Ray3f(mi.Point3f(*o), mi.Vector3f(*d))
    si = scene.ray_intersect(ray)
    assert si.is_valid(), (o, d)
    return {"origin": list(o), "dir": list(d), "p": [float(si.p[i]) for i in range(3)],
            "uv": [float(si.uv[0]), float(si.uv[1])]}


def shape_uv():
    out = {}
    # rectangle: [-1, 1]^2 in z = 0, normal +z
    rect = mi.load_dict({"type": "scene", "s": {"type": "rectangle"}})
    local = [(0.0, 0.0), (0.3, -0.4), (-0.9, 0.8), (0.95, 0.95), (-0.5, -0.99)]
    rows = [hit(rect, (x, y, 1.0), (0.0, 0.0, -1.0)) for x, y in local]
    for (x, y), r in zip(local, rows):
        assert np.allclose(r["uv"], [0.5 * x + 0.5, 0.5 * y + 0.5], atol=1e-6)
    out["rectangle"] = {"params": {"type": "rectangle"}, "hits": rows}
    # rectangle with to_world: scale (0.5, 1.5, 1), rotate 35 deg about (1, 1, 0)/sqrt2, translate (0.3, -0.2, 0.5)
    ops = [{"scale": [0.5, 1.5, 1.0]}, {"rotate": {"axis": [1, 1, 0], "angle": 35}}, {"translate": [0.3, -0.2, 0.5]}]
    tw = (mi.ScalarTransform4f().translate([0.3, -0.2, 0.5]) @ mi.ScalarTransform4f().rotate([1, 1, 0], 35)
          @ mi.ScalarTransform4f().scale([0.5, 1.5, 1.0]))
    rect2 = mi.load_dict({"type": "scene", "s": {"type": "rectangle", "to_world": tw}})
    n = tw @ mi.ScalarNormal3f(0, 0, 1)
    n = np.array([float(n[i]) for i in range(3)])
    n /= np.linalg.norm(n)
    rows = []
    for x, y in local:
        p = tw @ mi.ScalarPoint3f(x, y, 0)
        p = np.array([float(p[i]) for i in range(3)])
        d = -n + np.array([0.1, -0.05, 0.02])  # slightly oblique
        d /= np.linalg.norm(d)
        r = hit(rect2, tuple((p - d).tolist()), tuple(d.tolist()))
        assert np.allclose(r["uv"], [0.5 * x + 0.5, 0.5 * y + 0.5], atol=1e-5), (r, x, y)
        rows.append(dict(r, local=[x, y]))
    m = np.array([[float(tw.matrix[i][j]) for j in range(4)] for i in range(4)])
    out["rectangle_to_world"] = {"params": {"type": "rectangle", "to_world_ops": ops}, "to_world": m.tolist(),
                                 "hits": rows}
    # sphere
    c, rad = np.array([0.2, 0.1, -0.3]), 0.7
    sph = mi.load_dict({"type": "scene", "s": {"type": "sphere", "center": c.tolist(), "radius": rad}})
    rows = []
    dirs = [(0, 0, 1), (1, 0, 0), (0, 1, 0), (0, -1, 0), (-1, 0, 0), (0, 0, -1), (1, 0.001, 0.2), (1, -0.001, 0.2),
            (0.3, 0.5, 0.8), (-0.6, -0.2, 0.4), (0.2, -0.7, -0.5), (-0.1, 0.9, -0.3), (0.001, 0.0, 1.0)]
    for q in dirs:
        q = np.array(q, dtype=np.float64)
        q /= np.linalg.norm(q)
        target = c + rad * q
        o = c + 3.0 * q
        r = hit(sph, tuple(o.tolist()), tuple((-q).tolist()))
        rows.append(dict(r, local_dir=q.tolist()))
        lp = (np.array(r["p"]) - c) / rad
        phi = math.atan2(lp[1], lp[0])
        if phi < 0:
            phi += 2 * math.pi
        theta = math.acos(max(-1.0, min(1.0, lp[2])))
        du = (r["uv"][0] - phi / (2 * math.pi) + 0.5) % 1.0 - 0.5  # u = 0 and u = 1 are the same seam
        assert abs(du) < 1e-4 or abs(lp[2]) > 0.9999, (r, q)
        assert abs(r["uv"][1] - theta / math.pi) < 1e-4, (r, q)
    out["sphere"] = {"params": {"type": "sphere", "center": c.tolist(), "radius": rad}, "hits": rows}
    # OBJ mesh with vt, default flip_tex_coords (true)
    obj = mi.load_dict({"type": "scene", "s": {"type": "obj", "filename": os.path.join(TEX, "quad.obj")}})
    V, VT = np.array(QUAD_V), np.array(QUAD_VT)
    rows = []
    for tri, bary in [((0, 1, 2), (0.2, 0.3, 0.5)), ((0, 1, 2), (0.6, 0.3, 0.1)), ((0, 2, 3), (0.25, 0.25, 0.5)),
                      ((0, 2, 3), (0.1, 0.7, 0.2)), ((0, 2, 3), (0.8, 0.1, 0.1))]:
        p = sum(b * V[i] for b, i in zip(bary, tri))
        vt = sum(b * VT[i] for b, i in zip(bary, tri))
        r = hit(obj, (p[0] + 0.05, p[1] - 0.03, 1.0), tuple((np.array([-0.05, 0.03, p[2] - 1.0])).tolist()))
        assert np.allclose(r["p"], p, atol=1e-5), (r, p)
        assert np.allclose(r["uv"], [vt[0], 1.0 - vt[1]], atol=1e-5), (r, vt)
        rows.append(dict(r, vt_interpolated=vt.tolist()))
    out["obj"] = {"params": {"type": "obj", "filename": "textures/quad.obj"}, "vertices": QUAD_V, "vt": QUAD_VT,
                  "faces": "f 1/1 2/2 3/3, f 1/1 3/3 4/4", "hits": rows}
    return out


NOTES = [
    "to_uv: Mitsuba takes a 4x4 transform (ScalarTransform4f, XML <transform name=\"to_uv\">) and keeps rows 0-1 "
    "and columns 0, 1, 3 (an AffineTransform3f); 'to_uv' here is [m00, m01, m03, m10, m11, m13]: "
    "u' = a u + b v + c, v' = d u + e v + f, applied to si.uv before the lookup. to_uv_ops are applied in order "
    "(the first one to uv first); rotate is about z, counter-clockwise in (u, v).",
    "bitmap: uv (0, 0) is the top-left corner of the image (the first row of the file), u goes right, v goes down; "
    "pixel (x, y) covers u in [x/w, (x+1)/w], v in [y/h, (y+1)/h].",
    "nearest: pixel floor(u w), floor(v h), then wrapped; bilinear: pixel centres at ((x+0.5)/w, (y+0.5)/h), "
    "i.e. x = u w - 0.5, floor and fraction, both neighbours wrapped separately.",
    "wrap repeat: index mod size (floor mod, negatives wrap up); clamp: index clamped to [0, size-1]; mirror: "
    "index reflected with the edge pixel repeated (..., 1, 0 | 0, 1, ..., n-1 | n-1, ..., 0 | 0, ...), the same "
    "as mirroring u about every integer (u in [1, 2] -> 2 - u), also for bilinear.",
    "raw false: 8-bit sRGB images are decoded to linear with the exact sRGB curve at load time (interpolation in "
    "linear); raw true: value / 255, no decoding; float EXR: used as is either way. No clamping of values to [0, 1] "
    "(an EXR with values outside [0, 1] only gives a warning).",
    "grayscale PNG: one channel, decoded like the RGB ones, returned as (y, y, y).",
    "checkerboard: uv' = to_uv(uv); color0 where (frac(u') > 0.5) == (frac(v') > 0.5), else color1 "
    "(frac = x - floor(x); frac exactly 0.5 counts as the first half). Defaults color0 0.4, color1 0.2.",
    "rectangle: uv = (x/2 + 1/2, y/2 + 1/2) of the local point in [-1, 1]^2, whatever to_world is.",
    "sphere: local q = (p - center)/radius (to_world's rotation removed); u = atan2(q.y, q.x)/(2 pi) + (1 if negative), "
    "v = acos(q.z)/pi (v = 0 at +z); on the seam (q.y = 0, q.x > 0) rounding can give u = 1.0 instead of 0.",
    "obj: uv = interpolated vt with v flipped (1 - v) by the default flip_tex_coords = true.",
]


def main():
    tiles, gray = write_images()
    write_quad_obj()
    write_box_obj()
    data = {
        "mitsuba": f"{mi.__version__} {mi.variant()}",
        "notes": NOTES,
        "cases": texture_cases(),
        "tiles_pixels": pixel_values("textures/tiles.png", tiles,
                                     [(0, 0), (1, 0), (7, 0), (8, 0), (63, 0), (0, 1), (5, 9), (20, 30), (40, 17),
                                      (63, 47), (0, 47), (33, 24)]),
        "gray_pixels": pixel_values("textures/gray.png", gray, [(0, 0), (6, 0), (0, 4), (6, 4), (3, 2)]),
        "shape_uv": shape_uv(),
    }
    text = json.dumps(data, indent=1)
    # one line per list of numbers and per sample
    text = re.sub(r"\[\s+([-+0-9.e,\s]+?)\s+\]", lambda m: "[" + " ".join(m.group(1).split()) + "]", text)
    text = re.sub(r"\{\s+(\"(?:uv|origin|xy)\": [^{}]*?)\s+\}", lambda m: "{" + " ".join(m.group(1).split()) + "}", text)
    with open(os.path.join(HERE, "textures.json"), "w") as f:
        f.write(text + "\n")
    print(f"wrote {len(data['cases'])} texture cases, {sum(len(c['samples']) for c in data['cases'])} samples")


if __name__ == "__main__":
    main()
