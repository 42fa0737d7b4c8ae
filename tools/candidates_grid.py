#!/usr/bin/env python3
"""Labelled grid of `qsil candidates` pictures ([QSS] Fig. 8): rows = views, columns = methods.

Usage: python3 tools/candidates_grid.py DIR/summary.json OUT.png
Reads the summary written by `qsil candidates` and the PNGs next to it (Debian's python3-matplotlib).
"""
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.lines as mlines  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
from chart_common import run  # noqa: E402


def draw(s, base):
    """The grid of summary `s` (pictures in directory `base`): (figure, legend handles, legend
    columns, title, top of the layout)."""
    methods = s["methods"]
    views = ["camera", "overview"]
    fig, axes = plt.subplots(len(views), len(methods), figsize=(3.4 * len(methods), 3.4 * len(views) + 1.0),
                             squeeze=False)
    for c, m in enumerate(methods):
        for r, view in enumerate(views):
            ax = axes[r][c]
            ax.imshow(mpimg.imread(os.path.join(base, m["images"][r])))
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(f"{m['method']}\n{m['candidates']} candidates, {m['silhouettes']} silhouettes\n"
                             f"({m['upper_silhouettes']} upper); wasted mass "
                             f"{m['non_silhouette_mass'] + m['dead_end_mass']:.3f}", fontsize=9)
            if c == 0:
                ax.set_ylabel(f"{view} view", fontsize=10)
    handles = [mlines.Line2D([], [], color=(0, 0.63, 0), lw=2, label="candidate, not a silhouette"),
               mlines.Line2D([], [], color=(0.86, 0.12, 0.12), lw=2, label="candidate, silhouette"),
               mlines.Line2D([], [], color="black", marker="o", lw=0, label="shading point")]
    p = s["shading_point"]
    title = (f"{os.path.basename(s['scene'])}, {s['where']}: p = ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}), "
             f"{s['true_silhouettes']} true silhouettes ({s['true_silhouettes_upper']} upper)")
    return fig, handles, 3, title, 0.94


if __name__ == "__main__":
    run(draw, __doc__)
