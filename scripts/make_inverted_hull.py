#!/usr/bin/python3
"""Writes content/models/InvertedHull/InvertedHull.gltf: toon models outlined by inverted hulls.

usage: /usr/bin/python3 scripts/make_inverted_hull.py [OUT.gltf]

A toon "outline" is an inverted hull: a copy of the model a little larger, single-sided, its
triangles wound to face inwards, so that from outside only its far side is drawn (a rim around
the model). Here the model is a UV sphere of radius 1 and the hull a sphere of radius 1.06 with
every triangle's winding reversed (normals inwards). Three nodes, each a body and a hull:
  toon           single-sided hull;
  toon_mirrored  the same under scale (-1, 1, 1): the winding flips with the transform, so the
                 hull still faces inwards (glTF 2.0 "Transformations");
  toon_double    a double-sided hull (doubleSided: true), which casts from both faces.
content/scenes/toon_outline.json puts them on a ground plane under a sun. The file is small and
committed; rerun this script only to change it (the output is deterministic).
"""
import base64
import json
import math
import os
import struct
import sys

SEGMENTS = 32  # around
RINGS = 16     # pole to pole
HULL_SCALE = 1.06


def sphere(radius, inverted):
    """Positions, normals (outwards, or inwards when inverted) and triangle indices (CCW seen
    from outside, or reversed when inverted) of a UV sphere."""
    positions, normals, indices = [], [], []
    for r in range(RINGS + 1):
        theta = math.pi * r / RINGS
        for s in range(SEGMENTS + 1):
            phi = 2.0 * math.pi * s / SEGMENTS
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            positions.append(tuple(radius * c for c in n))
            normals.append(tuple(-c for c in n) if inverted else n)
    row = SEGMENTS + 1
    for r in range(RINGS):
        for s in range(SEGMENTS):
            a, b = r * row + s, (r + 1) * row + s
            quad = [(a, b, b + 1), (a, b + 1, a + 1)]  # CCW seen from outside
            for tri in quad:
                if r == 0 and tri == quad[1] or r == RINGS - 1 and tri == quad[0]:
                    continue  # degenerate at the poles
                indices.append(tuple(reversed(tri)) if inverted else tri)
    return positions, normals, indices


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        root, "content", "models", "InvertedHull", "InvertedHull.gltf")

    blob = bytearray()
    views, accessors = [], []

    def add(data, fmt, count, target, kind, component, minmax=None):
        while len(blob) % 4:
            blob.append(0)
        offset = len(blob)
        for item in data:
            blob.extend(struct.pack(fmt, *item))
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(blob) - offset,
                      "target": target})
        acc = {"bufferView": len(views) - 1, "componentType": component, "count": count,
               "type": kind}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    def add_mesh(radius, inverted):
        p, n, i = sphere(radius, inverted)
        bounds = ([round(-radius, 6)] * 3, [round(radius, 6)] * 3)
        pos = add(p, "<3f", len(p), 34962, "VEC3", 5126, bounds)
        nor = add(n, "<3f", len(n), 34962, "VEC3", 5126)
        ind = add(i, "<3H", 3 * len(i), 34963, "SCALAR", 5123)
        return {"POSITION": pos, "NORMAL": nor}, ind

    body_attr, body_ind = add_mesh(1.0, False)
    hull_attr, hull_ind = add_mesh(HULL_SCALE, True)

    materials = [
        {"name": "skin", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.55, 0.4, 1.0],
                                                   "metallicFactor": 0.0, "roughnessFactor": 0.8}},
        {"name": "outline", "pbrMetallicRoughness": {"baseColorFactor": [0.02, 0.02, 0.03, 1.0],
                                                      "metallicFactor": 0.0,
                                                      "roughnessFactor": 1.0}},
        {"name": "outline_double_sided", "doubleSided": True,
         "pbrMetallicRoughness": {"baseColorFactor": [0.02, 0.02, 0.03, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    ]
    meshes = [
        {"name": "body", "primitives": [{"attributes": body_attr, "indices": body_ind,
                                         "material": 0}]},
        {"name": "hull", "primitives": [{"attributes": hull_attr, "indices": hull_ind,
                                         "material": 1}]},
        {"name": "hull_double_sided", "primitives": [{"attributes": hull_attr,
                                                      "indices": hull_ind, "material": 2}]},
    ]
    nodes = [
        {"name": "toon", "translation": [-2.6, 1.2, 0.0], "children": [1, 2]},
        {"name": "toon_body", "mesh": 0},
        {"name": "toon_hull", "mesh": 1},
        {"name": "toon_mirrored", "translation": [0.0, 1.2, 0.0], "scale": [-1.0, 1.0, 1.0],
         "children": [4, 5]},
        {"name": "toon_mirrored_body", "mesh": 0},
        {"name": "toon_mirrored_hull", "mesh": 1},
        {"name": "toon_double", "translation": [2.6, 1.2, 0.0], "children": [7, 8]},
        {"name": "toon_double_body", "mesh": 0},
        {"name": "toon_double_hull", "mesh": 2},
    ]
    gltf = {
        "asset": {"version": "2.0", "generator": "kaskad scripts/make_inverted_hull.py"},
        "scene": 0,
        "scenes": [{"name": "inverted_hulls", "nodes": [0, 3, 6]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," +
                            base64.b64encode(bytes(blob)).decode("ascii")}],
    }
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    print(f"wrote {out} ({len(blob)} bytes of buffer)")


if __name__ == "__main__":
    main()
