#!/usr/bin/env python3
"""Small .serialized meshes written from the format description (Mitsuba 3.9's src/shapes/serialized.cpp),
and what Mitsuba 3 reads from them, for ppm-vk's test of its serialized reader.

Writes beside this script: serialized/shapes-v4.serialized (version 4: shape 0 a bent quad with float normals
and texture coordinates, shape 1 a tetrahedron in double precision with texture coordinates and vertex
colours, no normals), serialized/shapes-v3.serialized (version 3, the same two shapes: the format
matpreview.serialized uses) and serialized.json: for each file and shape_index, loaded with the to_world
below (and its matrix), Mitsuba's vertex_positions, vertex_normals, vertex_texcoords and faces (mi.traverse).

Run: pip install mitsuba; python3 scenes/references/serialized.py   (a second)
"""
import json
import os
import struct
import zlib

import mitsuba as mi

mi.set_variant("scalar_rgb")
HERE = os.path.dirname(os.path.abspath(__file__))
# Python's rotate does not normalise its axis: a unit one.
AXIS = [c / 14 ** 0.5 for c in (1, 2, 3)]
TO_WORLD = mi.ScalarTransform4f().translate([0.5, -1.0, 2.0]) @ mi.ScalarTransform4f().rotate(
    AXIS, 40.0) @ mi.ScalarTransform4f().scale([2.0, 0.5, 1.5])

QUAD = {
    "positions": [(-1, -1, 0), (1, -1, 0.25), (1, 1, 0), (-1, 1, -0.25)],
    "normals": [(0, 0, 1), (0.1, 0, 1), (0, 0.2, 1), (-0.3, 0.1, 1)],
    "uvs": [(0, 0), (1, 0), (1, 1), (0.25, 0.75)],
    "colors": None,
    "faces": [(0, 1, 2), (0, 2, 3)],
    "double": False,
    "name": "bent quad",
}
TETRA = {
    "positions": [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)],
    "normals": None,
    "uvs": [(0.1, 0.2), (0.9, 0.1), (0.5, 0.8), (0.3, 0.3)],
    "colors": [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)],
    "faces": [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)],
    "double": True,
    "name": "tetrahedron",
}


def shape_bytes(version, m):
    """One shape: the uncompressed header, then its zlib stream."""
    f = "d" if m["double"] else "f"
    flags = (0x2000 if m["double"] else 0x1000) | (1 if m["normals"] else 0) | (2 if m["uvs"] else 0) \
        | (8 if m["colors"] else 0)
    body = struct.pack("<I", flags)
    if version == 4:
        body += m["name"].encode() + b"\0"
    body += struct.pack("<QQ", len(m["positions"]), len(m["faces"]))
    for key in ["positions", "normals", "uvs", "colors"]:
        if m[key]:
            body += b"".join(struct.pack("<" + f * len(v), *v) for v in m[key])
    body += b"".join(struct.pack("<III", *t) for t in m["faces"])
    return struct.pack("<HH", 0x041C, version) + zlib.compress(body)


def write(version, path):
    data, offsets = b"", []
    for m in [QUAD, TETRA]:
        offsets.append(len(data))
        data += shape_bytes(version, m)
    o = "Q" if version == 4 else "I"
    data += b"".join(struct.pack("<" + o, x) for x in offsets) + struct.pack("<I", len(offsets))
    with open(path, "wb") as f:
        f.write(data)


def main():
    os.makedirs(os.path.join(HERE, "serialized"), exist_ok=True)
    out = []
    for version in [3, 4]:
        name = f"shapes-v{version}.serialized"
        path = os.path.join(HERE, "serialized", name)
        write(version, path)
        for index in [0, 1]:
            shape = mi.load_dict({"type": "serialized", "filename": path, "shape_index": index,
                                  "to_world": TO_WORLD})
            p = mi.traverse(shape)
            group = lambda key, k: [list(p[key][i:i + k]) for i in range(0, len(p[key]), k)]
            out.append({
                "file": name,
                "shape_index": index,
                "positions": group("vertex_positions", 3),
                "normals": group("vertex_normals", 3),
                "uvs": group("vertex_texcoords", 2),
                "faces": group("faces", 3),
            })
    doc = {
        "mitsuba_version": mi.__version__,
        "variant": "scalar_rgb",
        "to_world": "translate(0.5, -1, 2) rotate((1, 2, 3) / sqrt(14), 40 degrees) scale(2, 0.5, 1.5)",
        # Row by row, as the XML's <matrix value=".."/> takes it.
        "to_world_matrix": [x for row in TO_WORLD.matrix for x in row],
        "shapes": out,
    }
    with open(os.path.join(HERE, "serialized.json"), "w") as f:
        json.dump(doc, f, indent=1)
    print([(s["file"], s["shape_index"], len(s["positions"])) for s in out])


if __name__ == "__main__":
    main()
