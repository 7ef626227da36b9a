#!/usr/bin/env python3
"""Where the geometry lies in a `normal` view screenshot (editor_test.sh toggles: F frames a
model's entity): every pixel that is not black is a surface (n / 2 + 1/2 is never black).

  geometry_extent.py NORMAL.png

Prints "W H CX CY": the width and height of the geometry's bounding rectangle and its centre,
each as a fraction of the image's width or height (0 0 0 0 when there is no geometry).
"""
import sys

from changed_within import read_png


def main():
    width, height, channels, rows = read_png(sys.argv[1])
    xs, ys = [], []
    for y, row in enumerate(rows):
        for x in range(width):
            if any(row[x * channels + c] for c in range(min(channels, 3))):
                xs.append(x)
                ys.append(y)
    if not xs:
        print("0 0 0 0")
        return
    x0, x1, y0, y1 = min(xs), max(xs) + 1, min(ys), max(ys) + 1
    print(f"{(x1 - x0) / width:.3f} {(y1 - y0) / height:.3f} "
          f"{(x0 + x1) / 2 / width:.3f} {(y0 + y1) / 2 / height:.3f}")


if __name__ == "__main__":
    main()
