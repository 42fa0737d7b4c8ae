#!/usr/bin/env python3
"""Charts of a `qsil compare` run (Debian's python3 with python3-matplotlib and numpy).

Usage: python3 tools/plot_compare.py DIR [--title TEXT]

Reads DIR/results.json (and DIR/images/*.npy) and writes
  DIR/error_vs_time.png  relative MSE against wall time (or spp), log-log, one line per method,
                         the reference's noise floor dashed;
  DIR/grid.png           the reference's derivative, each method's at the largest budget, and
                         their squared-error maps.
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

COLORS = {"quadric": "#d62728", "quadric-box": "#ff7f0e", "vsphere": "#1f77b4", "vsphere-solid": "#17becf",
          "uniform": "#2ca02c", "fd": "#7f7f7f", "none": "#9467bd", "projective": "#8c564b", "was": "#e377c2",
          "regularized": "#bcbd22"}
MARKERS = {"quadric": "o", "quadric-box": "s", "vsphere": "^", "vsphere-solid": "v", "uniform": "D", "fd": "x",
           "none": "+", "projective": "P", "was": "*", "regularized": "h"}


def load(directory):
    """Returns the parsed results.json of a compare directory."""
    with open(os.path.join(directory, "results.json")) as f:
        return json.load(f)


def plot_error(res, path, title):
    """Draws relative MSE against wall time (equal-time mode) or spp (equal-sample mode)."""
    time_mode = res["mode"] == "time"
    fig, ax = plt.subplots(figsize=(6.4, 4.6), dpi=120)
    for m in res["methods"]:
        rows = sorted((r for r in res["rows"] if r["method"] == m), key=lambda r: r["target"])
        xs = [r["wall_seconds"] if time_mode else r["spp"] for r in rows]
        ys = [r["rel_mse"] for r in rows]
        pts = [(x, y) for x, y in zip(xs, ys) if y is not None and y > 0 and x > 0]
        if not pts:
            continue
        ax.plot(*zip(*pts), marker=MARKERS.get(m, "o"), color=COLORS.get(m), label=m, lw=1.6, ms=5)
        bad = sum(r["nonfinite_pixels"] for r in rows)
        if bad:
            ax.annotate(f"{bad} non-finite px", pts[-1], fontsize=7, color=COLORS.get(m))
    floor = res["reference"]["rel_noise_floor"]
    if floor and floor > 0:
        ax.axhline(floor, ls="--", color="k", lw=1, label="reference noise floor")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall-clock time per method (s)" if time_mode else "samples per pixel")
    ax.set_ylabel("relative MSE  (MSE / mean(ref²), unitless)")
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_grid(res, directory, path, title):
    """Draws the reference, each method at the largest budget, and squared-error maps."""
    img = os.path.join(directory, "images")
    ref = np.load(os.path.join(img, "reference.npy"))
    finite = np.abs(ref[np.isfinite(ref)])
    vmax = float(np.percentile(finite, 99.5)) if finite.size else 1.0
    vmax = vmax if vmax > 0 else 1.0
    methods = [m for m in res["methods"] if os.path.exists(os.path.join(img, m + ".npy"))]
    last = max(res["targets"])
    by_method = {r["method"]: r for r in res["rows"] if r["target"] == last}
    ims = {m: np.load(os.path.join(img, m + ".npy")) for m in methods}
    errs = {m: (np.nan_to_num(ims[m], nan=0, posinf=0, neginf=0) - ref) ** 2 for m in methods}
    allerr = np.concatenate([e.ravel() for e in errs.values()]) if errs else np.array([1.0])
    emax = float(np.percentile(allerr, 99.5)) if allerr.size else 1.0
    emax = emax if emax > 0 else 1.0
    emin = emax * 1e-4
    n = len(methods) + 1
    fig, axes = plt.subplots(2, n, figsize=(2.3 * n, 5.0), dpi=110, squeeze=False)
    unit = "s" if res["mode"] == "time" else "spp"
    axes[0][0].imshow(ref, cmap="RdBu_r", vmin=-vmax, vmax=vmax)
    axes[0][0].set_title("reference\n" + res["reference"]["description"], fontsize=7)
    se2_path = os.path.join(img, "reference_se2.npy")
    if os.path.exists(se2_path):
        axes[1][0].imshow(np.maximum(np.load(se2_path), emin), cmap="magma",
                          norm=matplotlib.colors.LogNorm(vmin=emin, vmax=emax))
        axes[1][0].set_title("reference se² (noise floor)", fontsize=7)
    for i, m in enumerate(methods, start=1):
        r = by_method.get(m, {})
        im0 = axes[0][i].imshow(ims[m], cmap="RdBu_r", vmin=-vmax, vmax=vmax)
        axes[0][i].set_title(f"{m}\n{r.get('spp', '?')} spp in {r.get('wall_seconds', 0):.2f} s", fontsize=7)
        im1 = axes[1][i].imshow(np.maximum(errs[m], emin), cmap="magma",
                                norm=matplotlib.colors.LogNorm(vmin=emin, vmax=emax))
        rel = r.get("rel_mse")
        axes[1][i].set_title(f"squared error\nrel. MSE {rel:.3g}" if rel is not None else "squared error", fontsize=7)
    for a in axes.ravel():
        a.set_xticks([])
        a.set_yticks([])
    if methods:
        fig.colorbar(im0, ax=list(axes[0]), shrink=0.8, label="∂I/∂θ (luminance)")
        fig.colorbar(im1, ax=list(axes[1]), shrink=0.8, label="squared error")
    fig.suptitle(f"{title} — largest budget {last:g} {unit}", fontsize=9)
    fig.savefig(path)
    plt.close(fig)


def main(argv):
    """Entry point: plot_compare.py DIR [--title TEXT]."""
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(argv) >= 2 else 2
    directory = argv[1]
    res = load(directory)
    title = argv[argv.index("--title") + 1] if "--title" in argv else \
        f"{os.path.basename(res['scene'])}: {', '.join(res['params'])} ({res['resolution'][0]}x{res['resolution'][1]})"
    plot_error(res, os.path.join(directory, "error_vs_time.png"), title)
    plot_grid(res, directory, os.path.join(directory, "grid.png"), title)
    print(f"plot_compare: {directory}/error_vs_time.png, {directory}/grid.png")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
