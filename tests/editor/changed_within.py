#!/usr/bin/env python3
"""Whether the pixels that differ between two screenshots all lie inside a mask taken from a
debug view of the frame before the change (editor_test.sh toggles):

  changed_within.py BEFORE.png AFTER.png VIEW.png geometry|penumbra|reflector

  geometry  VIEW is the `normal` view: geometry is every pixel that is not black (a surface's
            colour there is n / 2 + 1/2, never black), the background is black.
  penumbra  VIEW is the `visibility` view: the mask is where the visibility lies strictly
            between 0 and 1 (partly lit by the filter's taps).
  reflector VIEW is the `reflection` view: the mask is every pixel that is neither black (the
            background) nor the grey the view paints surfaces without a reflection map
            (kNotReflecting in editor/editor.cpp, 0.08: 20 in 8 bits).

Prints the counts and exits 0 when some pixel changed and every changed pixel is in the mask,
1 otherwise. The views are 8-bit: a visibility within 1/510 of 0 or 1 reads as 0 or 255 there,
so outside the penumbra mask a pixel may change by 1 in a channel (the light it gets differs by
under 1/510); a larger change outside it fails. Reads 8-bit, non-interlaced PNG (what the editor
writes) with the standard library.
"""
import struct
import sys
import zlib


def read_png(path):
    """(width, height, channels, rows of bytes)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG file")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    width, height, depth, colour, _, _, interlace = header
    channels = {0: 1, 2: 3, 4: 2, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace != 0:
        raise ValueError(f"{path}: only 8-bit, non-interlaced grey/RGB(A) PNG is read")
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous, i = [], bytearray(stride), 0
    for _ in range(height):
        kind, line = raw[i], bytearray(raw[i + 1:i + 1 + stride])
        i += 1 + stride
        for x in range(stride):
            a = line[x - channels] if x >= channels else 0
            b = previous[x]
            c = previous[x - channels] if x >= channels else 0
            if kind == 1:
                line[x] = (line[x] + a) & 255
            elif kind == 2:
                line[x] = (line[x] + b) & 255
            elif kind == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        previous = line
    return width, height, channels, rows


def main():
    if len(sys.argv) != 5 or sys.argv[4] not in ("geometry", "penumbra", "reflector"):
        print(__doc__)
        return 2
    before, after, view = (read_png(p) for p in sys.argv[1:4])
    if before[:2] != after[:2] or before[:2] != view[:2]:
        print(f"sizes differ: {before[:2]} {after[:2]} {view[:2]}")
        return 1
    width, height = before[0], before[1]
    changed = outside = in_mask = quantised = 0
    for y in range(height):
        rb, ra, rv = before[3][y], after[3][y], view[3][y]
        for x in range(width):
            pb = rb[x * before[2]:x * before[2] + 3]
            pa = ra[x * after[2]:x * after[2] + 3]
            v = rv[x * view[2]:x * view[2] + 3]
            if sys.argv[4] == "geometry":
                mask = any(v)
            elif sys.argv[4] == "reflector":
                mask = any(v) and tuple(v) != (20, 20, 20)
            else:
                mask = 0 < v[0] < 255
            in_mask += mask
            if pb != pa:
                changed += 1
                step = max(abs(p - q) for p, q in zip(pb, pa))
                if not mask:
                    quantised += step <= 1 and sys.argv[4] == "penumbra"
                    outside += not (step <= 1 and sys.argv[4] == "penumbra")
    print(f"{changed} pixels changed, {outside} of them outside the {sys.argv[4]} mask "
          f"({in_mask} of {width * height} pixels)"
          + (f", {quantised} more by 1 where the view rounds to 0 or 1" if quantised else ""))
    return 0 if changed > 0 and outside == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
