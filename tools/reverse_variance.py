#!/usr/bin/env python3
"""Variance of reverse mode's vertex gradient across seeds, for several configurations side by side:
the way to judge a change of reverse mode by what an optimiser sees.

For each configuration (a camera-hits rule, optionally with the control variate off) and each seed,
one qsil.reverse run of SHAPE's vertices with a fixed adjoint image of random signs (+-1 per pixel
and channel, its own seed, so that the loss adds every pixel's derivative instead of cancelling).
Three variances of the gradient across seeds, each summed over vertices and axes:
  projected    of sum_v g_v . d: the derivative along a translation d of the whole shape (what
               `qsil grad` with that parameter measures);
  per-vertex   of g itself;
  large-steps  of (I + lam L)^-1 g, the gradient of Large Steps' u = (I + lam L) x (lam 19, L the
               combinatorial Laplacian; python/qsil_shape.py): what the shape optimiser steps with.
and the median wall time of a run. With 3 seeds or more, each variance is followed by its range when
one seed is left out (each in turn; boundary_variance.leave_one_out_range): where one seed's rare
sample carries a sum, that range spans a factor of several, and two configurations whose ratio lies
within it are not ranked by this many seeds. Each configuration after the first is printed as a
ratio to the first (same seeds: the same paths where the configurations share them).

Configurations: adaptive, attached, detached (qsil.reverse's camera_hits, control variate on), and
the same names with a trailing 0 (camera_control_spp=0).

Usage: /usr/bin/python3 tools/reverse_variance.py SCENE --shape ID --direction X,Y,Z
       [--configs detached,adaptive,adaptive0] [--module build/python] [--spp 16] [--res 48]
       [--seeds 16] [--first-seed 1000] [--threads 2] [--lam 19]
"""
import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boundary_variance import with_range  # noqa: E402 (the one leave-one-seed-out formula and its text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--shape", required=True)
    ap.add_argument("--direction", required=True, help="the translation X,Y,Z of the projected derivative")
    ap.add_argument("--configs", default="detached,adaptive,adaptive0")
    ap.add_argument("--module", default=os.path.join(ROOT, "build", "python"), help="directory of the qsil module")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--res", type=int, default=48)
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--lam", type=float, default=19.0)
    args = ap.parse_args()
    if args.seeds < 2:
        sys.exit("reverse_variance: --seeds must be at least 2 (a variance needs two runs)")
    try:
        direction = np.array([float(x) for x in args.direction.split(",")])
        if direction.shape != (3,) or not np.isfinite(direction).all() or not np.linalg.norm(direction) > 0:
            raise ValueError
    except ValueError:
        sys.exit(f"reverse_variance: --direction must be three numbers X,Y,Z, not all 0 (got '{args.direction}')")
    direction /= np.linalg.norm(direction)
    configs = args.configs.split(",")
    for c in configs:
        if c.rstrip("0") not in ("adaptive", "attached", "detached"):
            sys.exit(f"reverse_variance: unknown configuration '{c}' (adaptive, attached, detached, with or "
                     "without a trailing 0)")
    sys.path.insert(0, os.path.abspath(args.module))
    import qsil  # noqa: E402 (the chosen build's module)
    import qsil_shape  # noqa: E402 (copied beside it by the build)
    import scipy.sparse  # noqa: E402
    import scipy.sparse.linalg  # noqa: E402

    try:
        scene = qsil.Scene(args.scene, {"res": str(args.res)})
        V, F = np.asarray(scene.vertices(args.shape)), np.asarray(scene.triangles(args.shape))
    except qsil.Error as e:
        sys.exit(f"reverse_variance: {e}")
    H, W = args.res, args.res
    adjoint = np.where(np.random.default_rng(7).random((H, W, 3)) < 0.5, -1.0, 1.0)
    M = scipy.sparse.identity(len(V), format="csr") + args.lam * qsil_shape.combinatorial_laplacian(F, len(V))
    solve = scipy.sparse.linalg.factorized(M.tocsc())
    rows = []
    for config in configs:
        grads, seconds = [], []
        for s in range(args.seeds):
            t0 = time.perf_counter()
            r = qsil.reverse(scene, [args.shape], adjoint, spp=args.spp, seed=args.first_seed + s,
                             threads=args.threads, camera_hits=config.rstrip("0"),
                             camera_control_spp=0 if config.endswith("0") else 4)
            seconds.append(time.perf_counter() - t0)
            grads.append(np.asarray(r["gradient"][args.shape]))
        g = np.array(grads)
        projected = g @ direction
        sums = projected.sum(axis=1)
        u = np.array([np.stack([solve(x[:, k]) for k in range(3)], axis=1) for x in g])
        row = dict(config=config, projected=sums.var(ddof=1), vertex=g.var(axis=0, ddof=1).sum(),
                   steps=u.var(axis=0, ddof=1).sum(), seconds=float(np.median(seconds)))
        rows.append(row)
        print(f"{config:10s} projected {sums.mean():.4g} +- {sums.std(ddof=1) / np.sqrt(args.seeds):.3g} "
              f"(variance {with_range(row['projected'], sums)}, largest |run - median| "
              f"{np.abs(sums - np.median(sums)).max():.3g})  per-vertex {with_range(row['vertex'], g)}  "
              f"large-steps {with_range(row['steps'], u)}  {row['seconds']:.3f} s", flush=True)
    first = rows[0]
    for row in rows[1:]:
        print(f"  {row['config']} / {first['config']}: projected {row['projected'] / first['projected']:.3f}, "
              f"per-vertex {row['vertex'] / first['vertex']:.3f}, large-steps {row['steps'] / first['steps']:.3f}, "
              f"time {row['seconds'] / first['seconds']:.3f}")


if __name__ == "__main__":
    main()
