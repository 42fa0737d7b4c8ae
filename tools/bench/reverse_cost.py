#!/usr/bin/env python3
"""Cost of a reverse-mode run against the primal image, with and without the probe pass (a
benchmark, not a test).

Usage: python3 tools/bench/reverse_cost.py [--build build] [--res 128] [--spp 4] [--pairs 6]
       [--threads 2] [--methods none,quadric] [SCENE:SHAPE ...]

For each scene and chosen shape (default: the bundled scenes' chart shapes) and each boundary
method, one process holds two qsil.ReverseEstimator: with the probe pass (ReverseConfig::probe_paths,
the default) and without it (every path over dual numbers). Per pair i it renders once (spp, seed
i) and runs both estimators on one fixed random adjoint image at seed i, in alternating order, so
that the machine's noise hits both. Prints a Markdown table of medians: the render's time, each
run's time and its ratio to the render, probe / duals (and the ratio of the fastest runs), and the
share of samples the probe completed. docs/experiments/2026-11-27-reverse-probe-pass.md is its
first record. Needs the Python module (target qsil_python; a Release build without DCHECKs
measures what a user gets).
"""
import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFAULT_CASES = [os.path.join(ROOT, "scenes", c) for c in
                 ("two-mirrors.xml:bunny", "spot-mirror.xml:spot", "shadow-quad.xml:object", "direct.xml:spot")]


def measure(qsil, scene_file, shape, method, res, spp, pairs, threads):
    """Medians of render and run times (s) with and without the probe, the fastest runs' ratio, and
    the share of samples the probe completed (over all pairs)."""
    sc = qsil.Scene(scene_file, {"res": str(res)})
    w = np.random.default_rng(0).uniform(-1, 1, (res, res, 3)) / (res * res * 3)
    estimators = {p: qsil.ReverseEstimator(sc, [shape], boundary=method, probe_paths=p) for p in (True, False)}
    render, runs, probed = [], {True: [], False: []}, 0
    for i in range(pairs):
        t0 = time.perf_counter()
        estimators[True].render(spp=spp, seed=i, threads=threads)
        render.append(time.perf_counter() - t0)
        for p in ((True, False) if i % 2 == 0 else (False, True)):
            t0 = time.perf_counter()
            r = estimators[p].run(w, spp=spp, seed=i, threads=threads)
            runs[p].append(time.perf_counter() - t0)
            if p:
                probed += r["probed"]
    return (float(np.median(render)), float(np.median(runs[True])), float(np.median(runs[False])),
            min(runs[True]) / min(runs[False]), probed / (res * res * spp * pairs))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cases", nargs="*", default=DEFAULT_CASES, help="SCENE:SHAPE (scene file and the shape's id)")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build directory with python/qsil*.so")
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--pairs", type=int, default=6, help="alternated pairs of runs per case")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--methods", default="none,quadric", help="boundary methods (comma list)")
    args = ap.parse_args()
    if args.res < 1 or args.spp < 1 or args.pairs < 1:
        ap.error("--res, --spp and --pairs must be >= 1")
    cases = []
    for c in args.cases:
        scene_file, sep, shape = c.rpartition(":")
        if not sep or not scene_file or not shape:
            ap.error("%r: expected SCENE:SHAPE" % c)
        if not os.path.isfile(scene_file):
            ap.error("%r: no such scene file" % scene_file)
        cases.append((scene_file, shape))
    sys.path.insert(0, os.path.join(args.build, "python"))
    import qsil  # noqa: E402  (built module)

    print("| scene, shape | boundary | render (s) | duals: run ÷ render | probe: run ÷ render | probe ÷ duals "
          "(fastest) | samples probed |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
    for scene_file, shape in cases:
        for method in args.methods.split(","):
            render, probe, duals, fastest, share = measure(qsil, scene_file, shape, method, args.res, args.spp,
                                                           args.pairs, args.threads)
            print("| %s, %s | %s | %.3f | %.1f | %.1f | %.2f (%.2f) | %.1f %% |"
                  % (os.path.basename(scene_file), shape, method, render, duals / render, probe / render,
                     probe / duals, fastest, 100 * share), flush=True)


if __name__ == "__main__":
    main()
