#!/usr/bin/env python3
"""Splits the efficiency gap between `grad` and finite differences into cost and variance, per scene:
the question to ask of a stability row where FD wins.

For each scene, over the same seeds: `qsil.grad` (one parameter, the default method) and central FD
with common random numbers (two `qsil.render`s at theta +- h, the shape moved through
Scene.set_vertices, h = `qsil fd`'s default step h0, read from its output), both at --spp. Per
method: the per-pixel variance across seeds (channel mean) summed over the image, its range when
one seed is left out (boundary_variance.leave_one_out_range), and the mean wall time per run. Then
  cost      grad's time / FD's time (FD: its two renders),
  variance  grad's variance sum / FD's, at equal spp,
  gap       their product: how many times FD is more efficient per pixel (> 1: FD wins; the
            stability study's FD / quadric ratio, less FD's step bias, which this does not see).
Only translations (ID:translate:X,Y,Z) are supported: FD moves every vertex of the shape by +-h.

Usage: /usr/bin/python3 tools/fd_gap.py [--module build/python] [--qsil build/qsil] [--spp 64] [--res 48]
       [--seeds 16] [--first-seed 1000] [--threads 2] SCENE:PARAM ...
"""
import argparse
import os
import re
import subprocess
import sys
import time
import warnings

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boundary_variance import leave_one_out_range  # noqa: E402


def parse_target(text):
    """'SCENE:ID:translate:X,Y,Z' -> (scene path, parameter, shape id, direction (3,)): the direction as
    given, for qsil moves the shape by theta (X, Y, Z) (a translation is not normalised)."""
    m = re.fullmatch(r"(.+\.xml):(([^:]+):translate:([^:]+))", text)
    if not m:
        raise ValueError(f"'{text}' is not SCENE.xml:ID:translate:X,Y,Z")
    d = np.array([float(x) for x in m.group(4).split(",")])
    if d.shape != (3,) or not np.isfinite(d).all() or not np.linalg.norm(d) > 0:
        raise ValueError(f"'{text}': the translation must be three numbers, not all 0")
    return m.group(1), m.group(2), m.group(3), d


def default_step(qsil_cli, scene, param, res):
    """qsil fd's default step h0 for `param` (its `h0 = ...` line)."""
    out = subprocess.run([qsil_cli, "fd", scene, "--param", param, "--spp", "1", "-D", f"res={res}", "-q",
                          "-o", os.devnull], capture_output=True, text=True)
    m = re.search(r"h0 = ([0-9.eE+-]+)", out.stdout + out.stderr)
    if out.returncode != 0 or not m:
        raise RuntimeError(f"qsil fd on {scene} gave no step: {(out.stderr or out.stdout).strip()}")
    return float(m.group(1))


def variance_line(runs):
    """(summed per-pixel variance, its leave-one-seed-out range) of runs (seeds x H x W)."""
    lo, hi = leave_one_out_range(runs)
    return runs.var(axis=0, ddof=1).sum(), lo, hi


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("targets", nargs="+", help="SCENE.xml:ID:translate:X,Y,Z")
    ap.add_argument("--module", default=os.path.join(ROOT, "build", "python"))
    ap.add_argument("--qsil", default=os.path.join(ROOT, "build", "qsil"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", type=int, default=48)
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    if args.seeds < 3:
        sys.exit("fd_gap: --seeds must be at least 3 (a variance and its leave-one-out range)")
    try:
        targets = [parse_target(t) for t in args.targets]
    except ValueError as e:
        sys.exit(f"fd_gap: {e}")
    sys.path.insert(0, os.path.abspath(args.module))
    import qsil  # noqa: E402 (the chosen build's module)
    warnings.simplefilter("ignore", RuntimeWarning)  # grad's dominant-pixel warning: the point here
    print("| scene | grad variance | FD variance (h0) | grad s/run | FD s/run | cost | variance | gap |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for scene_path, param, shape, direction in targets:
        try:
            h = default_step(args.qsil, scene_path, param, args.res)
            scene = qsil.Scene(scene_path, {"res": str(args.res)})
            v0 = np.asarray(scene.vertices(shape)).copy()
        except (RuntimeError, qsil.Error) as e:
            sys.exit(f"fd_gap: {e}")
        g, f, tg, tf = [], [], [], []
        for s in range(args.seeds):
            seed = args.first_seed + s
            t0 = time.perf_counter()
            _, d = qsil.grad(scene, [param], spp=args.spp, seed=seed, threads=args.threads)
            tg.append(time.perf_counter() - t0)
            g.append(np.asarray(d)[0].mean(axis=2))
            t0 = time.perf_counter()
            scene.set_vertices(shape, v0 + h * direction)
            a = np.asarray(qsil.render(scene, spp=args.spp, seed=seed, threads=args.threads))
            scene.set_vertices(shape, v0 - h * direction)
            b = np.asarray(qsil.render(scene, spp=args.spp, seed=seed, threads=args.threads))
            tf.append(time.perf_counter() - t0)
            scene.set_vertices(shape, v0)
            f.append(((a - b) / (2 * h)).mean(axis=2))
        vg, glo, ghi = variance_line(np.array(g))
        vf, flo, fhi = variance_line(np.array(f))
        cost, var = np.mean(tg) / np.mean(tf), vg / vf
        name = os.path.splitext(os.path.basename(scene_path))[0]
        print(f"| {name} | {vg:.4g} ({glo:.4g}–{ghi:.4g}) | {vf:.4g} ({flo:.4g}–{fhi:.4g}) | {np.mean(tg):.3f} | "
              f"{np.mean(tf):.3f} | {cost:.2f} | {var:.2f} | {cost * var:.2f} |", flush=True)


if __name__ == "__main__":
    main()
