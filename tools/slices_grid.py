#!/usr/bin/env python3
"""Labelled grid of `qsil slices` images ([QSS] Fig. 7): rows = planes, columns = tests.

Usage: python3 tools/slices_grid.py DIR/summary.json OUT.png
Reads the summary written by `qsil slices` and the PNGs next to it (Debian's python3-matplotlib).
"""
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.patches as mpatches  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
from chart_common import run  # noqa: E402

COLOURS = [((225, 225, 225), "no silhouette, rejected"), ((60, 110, 190), "silhouette, accepted"),
           ((245, 150, 30), "false accept"), ((230, 0, 230), "false reject (bug)")]


def draw(s, base):
    """The grid of summary `s` (pictures in directory `base`): (figure, legend handles, legend
    columns, title, top of the layout)."""
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
    title = (f"rejection tests on node '{s['node']}' ({s['edges']} edges), "
             f"{s['resolution']}x{s['resolution']} points per plane")
    return fig, handles, 4, title, 0.95


if __name__ == "__main__":
    run(draw, __doc__)
