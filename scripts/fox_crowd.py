#!/usr/bin/env python3
"""Writes a scene of N Foxes in a grid (content/scenes/fox_walk.json's light and ground), for the
skinning cost benchmark: python3 scripts/fox_crowd.py N OUT.json [--still] [--no-shadows]. --still
stops every clip (the same meshes, posed once and then kept); --no-shadows makes the Foxes cast no
shadow, so that playing and still differ by posing alone, not by shadow layers drawn again."""
import json, math, os, sys

n, out = int(sys.argv[1]), sys.argv[2]
still = "--still" in sys.argv[3:]
no_shadows = "--no-shadows" in sys.argv[3:]
here = os.path.dirname(os.path.abspath(__file__))
with open(os.path.join(here, "..", "content", "scenes", "fox_walk.json")) as f:
    scene = json.load(f)
model = os.path.relpath(os.path.join(here, "..", "content", "models", "Fox", "glTF", "Fox.gltf"),
                        os.path.dirname(os.path.abspath(out)))
side = max(1, math.ceil(math.sqrt(n)))
entities = [e for e in scene["entities"] if e["name"] not in ("walker", "crate")]
for k in range(n):
    x, z = (k % side - (side - 1) / 2) * 1.2, (k // side - (side - 1) / 2) * 1.6
    entities.append({"name": f"fox{k}", "transform": {"translation": [x, 0, z], "euler_deg": [0, 90, 0],
                                                      "scale": [0.02, 0.02, 0.02]},
                     "model": {"path": model},
                     "animation": {"Survey": {"playing": False},
                                   "Walk": {"playing": not still, "time": 0.1 * k}}})
    if no_shadows:
        entities[-1]["renderer"] = {"cast_shadows": False}
for e in entities:
    if e["name"] == "ground":
        e["transform"]["scale"] = [max(20, side * 2.5)] * 3
    if e["name"] == "camera":
        d = max(4.2, side * 1.6)
        e["transform"] = {"translation": [0.5, d * 0.6, d], "look_at": [0, 0.4, 0]}
scene["entities"] = entities
with open(out, "w") as f:
    json.dump(scene, f, indent=1)
