#!/usr/bin/env python3
"""Labelled grid of `qsil slices` images ([QSS] Fig. 7): rows = planes, columns = tests.

Usage: python3 tools/slices_grid.py DIR/summary.json OUT.png
Reads the summary written by `qsil slices` and the PNGs next to it (Debian's python3-matplotlib).
"""
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.patches as mpatches  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

COLOURS = [((225, 225, 225), "no silhouette, rejected"), ((60, 110, 190), "silhouette, accepted"),
           ((245, 150, 30), "false accept"), ((230, 0, 230), "false reject (bug)")]


def main(summary_path, out_path):
    with open(summary_path) as f:
        s = json.load(f)
    base = os.path.dirname(summary_path)
    planes = s["planes"]
    tests = list(planes[0]["tests"].keys())
    fig, axes = plt.subplots(len(planes), len(tests), figsize=(3.0 * len(tests), 3.2 * len(planes) + 0.8),
                             squeeze=False)
    for r, plane in enumerate(planes):
        for c, name in enumerate(tests):
            t = plane["tests"][name]
            ax = axes[r][c]
            ax.imshow(mpimg.imread(os.path.join(base, t["image"])), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            title = f"{name}\nfalse accepts {100.0 * t['false_accept_rate']:.1f}%"
            if t["false_rejects"]:
                title += f", FALSE REJECTS {t['false_rejects']}"
            ax.set_title(title, fontsize=10)
            if c == 0:
                ax.set_ylabel(f"plane {plane['plane']} (h = {plane['height']:g})", fontsize=10)
    handles = [mpatches.Patch(color=tuple(v / 255.0 for v in rgb), label=label) for rgb, label in COLOURS]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=9, frameon=False)
    fig.suptitle(f"rejection tests on node '{s['node']}' ({s['edges']} edges), "
                 f"{s['resolution']}x{s['resolution']} points per plane", fontsize=11)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    fig.savefig(out_path + ".tmp.png", dpi=100)
    os.replace(out_path + ".tmp.png", out_path)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
