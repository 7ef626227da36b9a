#!/usr/bin/env python3
"""Validates every scene and material file under content/ (and, given PLAYBACK_DIR, every
playback file under it) against the JSON Schemas that `kaskad schema` generates from the field
tables and the playback reader's limits, with a real validator (python3-jsonschema). Then checks
that the schemas refuse a few files the readers refuse, so that a schema accepting anything fails.

usage: validate_content.py REFERENCE_DIR CONTENT_DIR [PLAYBACK_DIR]
"""
import copy
import json
import pathlib
import sys

import jsonschema


def validator(path):
    schema = json.loads(path.read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


# Changes to a good playback file that make the reader refuse it: the schema must refuse them too.
BAD_PLAYBACKS = {
    "unknown top-level key": lambda d: d.update(speed=2),
    "no frames": lambda d: d.update(frames=0),
    "unknown interpolation": lambda d: d["timeline"][0].update(interpolation="cubic"),
    "fov_y_deg on an entity key": lambda d: d["timeline"][0]["keys"][0].update(fov_y_deg=40),
    "a key with position and move": lambda d: d["timeline"][0]["keys"][0].update(move=[0, 0, 0]),
    "an event with set and remove": lambda d: d["timeline"].append(
        {"frame": 1, "set": "shadow.filter=none", "remove": "box_floating"}),
    "an event with frame and t": lambda d: d["timeline"].append({"frame": 1, "t": 0, "set": "a=1"}),
    "an unknown expectation": lambda d: d["expect"].update(misclassified=1),
}


def refuse_bad_playbacks(playback_v, good):
    if not playback_v.is_valid(good):
        print("FAIL the playback schema refuses the good file the bad ones are made from")
        return 1
    failed = 0
    for name, change in BAD_PLAYBACKS.items():
        doc = copy.deepcopy(good)
        change(doc)
        if playback_v.is_valid(doc):
            print(f"FAIL the playback schema accepts a file with {name}")
            failed += 1
    return failed


def main():
    reference, content = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    playback = pathlib.Path(sys.argv[3]) if len(sys.argv) > 3 else None
    groups = [
        (validator(reference / "scene.schema.json"), sorted((content / "scenes").rglob("*.json"))),
        (validator(reference / "material.schema.json"), sorted((content / "materials").glob("*.json"))),
    ]
    if playback:
        playback_files = sorted(playback.rglob("*.json"))
        if not playback_files:
            print("FAIL no playback files found under", playback)
            return 1
        groups.append((validator(reference / "playback.schema.json"), playback_files))
    failed = checked = 0
    for v, files in groups:
        for f in files:
            checked += 1
            errors = sorted(v.iter_errors(json.loads(f.read_text())), key=lambda e: list(e.path))
            for e in errors[:5]:
                print(f"FAIL {f}: /{'/'.join(map(str, e.path))}: {e.message}")
            failed += bool(errors)
    if checked == 0:
        print("FAIL no content files found under", content)
        return 1

    # Files the readers refuse: the schema must refuse them too.
    scene_v = groups[0][0]
    default = json.loads((content / "scenes" / "default.json").read_text())
    bad = {
        "unknown top-level key": {**default, "rendr": {}},
        "map_size not a power of two": {**default, "shadow": {"map_size": 100}},
        "lambda above 1": {**default, "shadow": {"lambda": 1.5}},
        "unknown technique": {**default, "shadow": {"technique": "raytraced"}},
        "even vsm_blur": {**default, "shadow": {"vsm_blur": 4}},
        "exposure and exposure_ev": {**default, "render": {"exposure": 1, "exposure_ev": 0}},
    }
    entity = copy.deepcopy(default)
    entity["entities"][0]["lihgt"] = {}
    bad["unknown entity section"] = entity
    for name, doc in bad.items():
        if scene_v.is_valid(doc):
            print(f"FAIL the scene schema accepts a file with {name}")
            failed += 1
    tried = len(bad)
    if playback:
        failed += refuse_bad_playbacks(groups[2][0], json.loads((playback / "moving_caster.json").read_text()))
        tried += len(BAD_PLAYBACKS)
    print(f"{checked} content files validated, {tried} bad files tried; {failed} failures")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
