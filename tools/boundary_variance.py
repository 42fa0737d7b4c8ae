#!/usr/bin/env python3
"""Variance of the boundary term alone, and of the interior term, across seeds: the way to judge a
change of the edge choice (an importance, a mixture) whose effect the interior term's noise would
hide in a total.

The boundary term of seed s is grad(s) - grad(s, boundary="none"): the boundary term draws from a
stream of its own, so both runs trace the same paths and their difference is the boundary term
(primary and secondary) exactly. Per seed and in total it prints nothing but the summary:
  boundary  sum over pixels of the per-pixel variance across seeds (channel mean, derivative 0),
            its range when one seed is left out (each in turn: a sum that one seed's rare sample
            carries spans a factor of several, and then this many seeds cannot rank two builds),
            the share of that sum in the top 1 % of pixels, the image sum's mean +- its s.e.;
  interior  the same for grad(s, boundary="none");
  seconds   grad's mean wall time per run (the boundary method's; threads as given).
Two builds compare side by side by running this with each one's module (--module), same seeds.

Usage: /usr/bin/python3 tools/boundary_variance.py SCENE --param P [--module build/python]
       [--boundary quadric] [--sppi 0] [--forest-guide-training 0] [--spp 64] [--res 48] [--seeds 16] [--first-seed 100] [--threads 2]
"""
import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def leave_one_out_range(runs):
    """(smallest, largest) summed per-pixel variance over the seeds with one seed left out, each seed
    in turn (runs: seeds x H x W, at least 3 seeds). Where one seed's rare sample carries the sum, the
    range spans a factor of several: two builds whose sums differ by less than their ranges are not
    ranked by this many seeds."""
    runs = np.asarray(runs, dtype=float)
    n = runs.shape[0]
    if n < 3:
        raise ValueError(f"leave_one_out_range needs at least 3 seeds (got {n})")
    # Deviations d from the all-seed mean: the other seeds' deviations sum to -d_i, so their squared
    # deviations about their own mean sum to sum_j d_j^2 - d_i^2 n / (n - 1) (no cancellation of
    # large means).
    d = runs - runs.mean(axis=0)
    ss = (d * d).sum(axis=0)
    sums = [float(np.maximum(ss - d[i] * d[i] * n / (n - 1), 0.0).sum() / (n - 2)) for i in range(n)]
    return min(sums), max(sums)


def with_range(total, runs):
    """`total` formatted, with the leave-one-seed-out range of runs (seeds x ...) where there are at
    least 3 seeds (leave_one_out_range)."""
    if len(runs) < 3:
        return f"{total:.4g}"
    lo, hi = leave_one_out_range(runs)
    return f"{total:.4g} (one seed left out: {lo:.4g}..{hi:.4g})"


def summary(name, runs):
    """One line: per-pixel variance summed, its leave-one-seed-out range (leave_one_out_range; with
    at least 3 seeds), its top-1 % share, image sum +- s.e. (runs: seeds x H x W)."""
    var = runs.var(axis=0, ddof=1)
    flat = np.sort(var.ravel())[::-1]
    top = flat[:max(1, flat.size // 100)].sum() / flat.sum() if flat.sum() > 0 else float("nan")
    sums = runs.sum(axis=(1, 2))
    return (f"{name:9s} variance sum {with_range(var.sum(), runs)}  top-1% share {top:.2f}  "
            f"image sum {sums.mean():.4g} +- {sums.std(ddof=1) / np.sqrt(len(sums)):.3g}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--param", required=True)
    ap.add_argument("--module", default=os.path.join(ROOT, "build", "python"), help="directory of the qsil module")
    ap.add_argument("--boundary", default="quadric")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", type=int, default=48)
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--first-seed", type=int, default=100)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--sppi", type=float, default=0,
                    help="secondary boundary-term traversals per shading point (0: the method's default)")
    ap.add_argument("--forest-guide-training", type=int, default=0,
                    help="the quadric methods' guided edge choice: training spp per pass (0: none; qsil grad --help)")
    args = ap.parse_args()
    if args.seeds < 2:
        sys.exit("boundary_variance: --seeds must be at least 2 (a variance needs two runs)")
    sys.path.insert(0, os.path.abspath(args.module))
    import qsil  # noqa: E402 (the chosen build's module)

    try:
        scene = qsil.Scene(args.scene, {"res": str(args.res)})
    except qsil.Error as e:
        sys.exit(f"boundary_variance: {e}")
    boundary, interior, seconds = [], [], 0.0
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        t0 = time.time()
        _, g = qsil.grad(scene, [args.param], spp=args.spp, seed=seed, threads=args.threads, boundary=args.boundary,
                         sppi=args.sppi, forest_guide_training=args.forest_guide_training)
        seconds += time.time() - t0
        _, n = qsil.grad(scene, [args.param], spp=args.spp, seed=seed, threads=args.threads, boundary="none")
        boundary.append((g[0] - n[0]).mean(axis=-1))
        interior.append(n[0].mean(axis=-1))
    guide = f" guided ({args.forest_guide_training} training spp)" if args.forest_guide_training else ""
    guide += f", sppi {args.sppi:g}" if args.sppi else ""
    print(f"{args.scene} {args.param} {args.boundary}{guide}, {args.spp} spp, {args.res}^2, seeds "
          f"{args.first_seed}..{args.first_seed + args.seeds - 1}")
    print(summary("boundary", np.array(boundary)))
    print(summary("interior", np.array(interior)))
    print(f"seconds   {seconds / args.seeds:.3f} per grad run")
    return 0


if __name__ == "__main__":
    sys.exit(main())
