#!/usr/bin/env python3
"""Writes a copy of a .gltf whose textures are WebP images (EXT_texture_webp), for trying and
testing WebP content: python3 scripts/gltf_to_webp.py IN.gltf OUT_DIR [--keep-fallback].

Each image the file names by uri is converted with oiiotool (OpenImageIO) to OUT_DIR/NAME.webp
(lossless), its buffers are copied beside it, and every texture gets
"extensions": {"EXT_texture_webp": {"source": K}}. Without --keep-fallback the texture's own
source is removed and the extension is required (a reader without WebP must refuse the file);
with it, the original PNG/JPEG stays as the fallback."""
import json
import os
import shutil
import subprocess
import sys


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    src, out = argv[1], argv[2]
    keep = "--keep-fallback" in argv[3:]
    with open(src) as f:
        doc = json.load(f)
    here = os.path.dirname(os.path.abspath(src))
    os.makedirs(out, exist_ok=True)
    for b in doc.get("buffers", []):
        uri = b.get("uri", "")
        if uri and not uri.startswith("data:"):
            shutil.copyfile(os.path.join(here, uri), os.path.join(out, os.path.basename(uri)))
            b["uri"] = os.path.basename(uri)
    images = doc.get("images", [])
    webp_of = {}
    for k, image in enumerate(list(images)):
        uri = image.get("uri", "")
        if not uri or uri.startswith("data:"):
            continue
        name = os.path.splitext(os.path.basename(uri))[0] + ".webp"
        subprocess.run(["oiiotool", os.path.join(here, uri), "--attrib", "compression", "lossless",
                        "-o", os.path.join(out, name)], check=True)
        if keep:
            shutil.copyfile(os.path.join(here, uri), os.path.join(out, os.path.basename(uri)))
            image["uri"] = os.path.basename(uri)
        webp_of[k] = len(images)
        images.append({"uri": name, "mimeType": "image/webp"})
    for t in doc.get("textures", []):
        s = t.get("source")
        if s in webp_of:
            t.setdefault("extensions", {})["EXT_texture_webp"] = {"source": webp_of[s]}
            if not keep:
                del t["source"]
    if not keep:  # the converted originals are no texture's source any more
        kept = [i for i in range(len(images)) if i not in webp_of]
        remap = {old: new for new, old in enumerate(kept)}
        doc["images"] = [images[i] for i in kept]
        for t in doc.get("textures", []):
            if "source" in t:
                t["source"] = remap[t["source"]]
            ext = t.get("extensions", {}).get("EXT_texture_webp")
            if ext:
                ext["source"] = remap[ext["source"]]
    doc["extensionsUsed"] = sorted(set(doc.get("extensionsUsed", [])) | {"EXT_texture_webp"})
    if not keep:
        doc["extensionsRequired"] = sorted(set(doc.get("extensionsRequired", [])) | {"EXT_texture_webp"})
    path = os.path.join(out, os.path.basename(src))
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
    print("wrote " + path)


if __name__ == "__main__":
    main(sys.argv)
