#!/usr/bin/env python3
"""Validates every scene and material file under content/ (and the playback files of
tests/playback when a playback schema is given) against the JSON Schemas that `kaskad schema`
generates from the field tables, with a real validator (python3-jsonschema). Then checks that
the schemas refuse a few files the readers refuse, so that a schema accepting anything fails.

usage: validate_content.py REFERENCE_DIR CONTENT_DIR
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


def main():
    reference, content = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    groups = [
        (validator(reference / "scene.schema.json"), sorted((content / "scenes").rglob("*.json"))),
        (validator(reference / "material.schema.json"), sorted((content / "materials").glob("*.json"))),
    ]
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
    print(f"{checked} content files validated, {len(bad)} bad files tried; {failed} failures")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
