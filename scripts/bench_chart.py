#!/usr/bin/python3
"""Speed against accuracy charts for `kaskad bench`: one PNG per scene from bench.csv.

usage: /usr/bin/python3 scripts/bench_chart.py BENCH.csv OUT_DIR [ERROR_COLUMN]
Without ERROR_COLUMN: OUT_DIR/<scene>.png (misclassified_pct) and, when the CSV has stability
results, OUT_DIR/<scene>_flicker.png (flicker: stability under camera motion).
x: median frame ms; y: ERROR_COLUMN (default misclassified_pct); the Pareto front (no other
configuration is both faster and more accurate) is highlighted. Points are numbered; the list
beside the plot names each number's settings (values only, keys in the list's heading), and
Pareto points also carry their settings on the plot.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def pareto(points):
    """Indices of points not dominated in (x, y), both minimised."""
    front = []
    for i, (x, y) in enumerate(points):
        dominated = any(
            (x2 <= x and y2 <= y) and (x2 < x or y2 < y) for j, (x2, y2) in enumerate(points) if j != i
        )
        if not dominated:
            front.append(i)
    return sorted(front, key=lambda i: points[i][0])


def short_label(config):
    """'cascade_count=1 fit_mode=crop' -> ('cascade_count fit_mode', '1 crop')."""
    parts = [p.split("=", 1) for p in config.split() if "=" in p]
    if not parts:
        return "", config
    return " ".join(k for k, _ in parts), " ".join(v for _, v in parts)


def chart(rows, column, out_dir, suffix):
    """One chart per scene of `column` against frame ms; returns the files written."""
    by_scene = {}
    for r in rows:
        by_scene.setdefault(r["scene"], []).append(r)
    written = []
    for scene, rs in by_scene.items():
        pts, labels = [], []
        for r in rs:
            x, y = float(r["frame_ms"]), float(r[column])
            if math.isfinite(x) and math.isfinite(y):
                pts.append((x, y))
                labels.append(r["config"])
        fig, ax = plt.subplots(figsize=(12, 6.5), dpi=110)
        keys = short_label(labels[0])[0] if labels else ""
        names = [short_label(t)[1] for t in labels]
        if pts:
            front = pareto(pts)
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], color="#8899aa", label="configuration")
            ax.plot([pts[i][0] for i in front], [pts[i][1] for i in front], "-o", color="#d04020",
                    label="Pareto front")
            for i, (x, y) in enumerate(pts):
                text = f"{i + 1}: {names[i]}" if i in front else str(i + 1)
                ax.annotate(text, (x, y), textcoords="offset points", xytext=(4, 4),
                            fontsize=7 if i in front else 6,
                            color="#a02010" if i in front else "#333333")
            listing = "\n".join(f"{i + 1:>2}  {n}" + ("  *" if i in front else "")
                                for i, n in enumerate(names))
            fig.text(0.74, 0.95, f"{keys}\n\n{listing}\n\n* Pareto front", fontsize=7,
                     family="monospace", va="top")
            fig.subplots_adjust(right=0.72)
        ax.set_xlabel("frame time, median (ms)")
        ax.set_ylabel(column.replace("_", " "))
        ax.set_title(f"{scene}: speed against {'stability' if column == 'flicker' else 'accuracy'}")
        ax.grid(True, alpha=0.3)
        ax.legend()
        out = os.path.join(out_dir, f"{scene}{suffix}.png")
        # Atomic, as every output of Kaskad (docs/guide/bad_input.md, "Outputs"): a temporary file in the same
        # folder, synced, then renamed over the previous chart.
        tmp = os.path.join(out_dir, f".{scene}{suffix}.tmp.png")
        try:
            fig.savefig(tmp)
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
            os.replace(tmp, out)
        except BaseException:
            if os.path.exists(tmp):
                os.remove(tmp)
            raise
        plt.close(fig)
        written.append(out)
    return written


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    path, out_dir = sys.argv[1], sys.argv[2]
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{path}: no rows")
    jobs = [(sys.argv[3], "")] if len(sys.argv) > 3 else [("misclassified_pct", "")]
    if len(sys.argv) <= 3 and "flicker" in rows[0]:
        if any(math.isfinite(float(r["flicker"])) for r in rows):
            jobs.append(("flicker", "_flicker"))
    for column, suffix in jobs:
        if column not in rows[0]:
            sys.exit(f"{path}: no column '{column}'")
        for out in chart(rows, column, out_dir, suffix):
            print(f"wrote     {os.path.abspath(out)}")


if __name__ == "__main__":
    main()
