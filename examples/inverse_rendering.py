#!/usr/bin/env python3
"""Recover a shape from images of its reflection ([QSS] Sec. 5.5 style), with qsil's reverse mode.

The scene is scenes/spot-mirror.xml: the camera sees the object ONLY in a rough GGX mirror
(alpha 0.01) under an environment map, so the object's outline in the images moves only through
the secondary boundary term (silhouettes seen from points on the mirror). Targets: renders of
Spot turned to four angles about the vertical axis and tilted by +-30 degrees (the object is
turned, not the camera: view i sets the vertices to R_i x and turns the gradient back with R_i^T).
The optimisation starts from a sphere and moves every vertex:

    loss  = mean over views and pixel-channels of (I - T)^2
    dL/dx = ReverseEstimator.run(adjoint = 2 (I - T) / n), I = ReverseEstimator.render with its own
            seed (so the product of the two estimates is unbiased)
    step  = qsil_shape.LargeSteps: uniform Adam on u = (I + lam L) x (Nicolet et al. 2021)
    remesh: at equal shares of the time, qsil.remesh (CGAL isotropic remeshing) to half the mean
            edge length, the step size times --lr-decay, the Adam moments reset

One qsil.ReverseEstimator per view, set up once per mesh: update() refits its edge forest after
each step. Each boundary method (quadric: the edge forest; vsphere: Li 2019's tree) runs for the
same wall time; at ten points the shape is scored outside the budget: the loss of fixed-seed
64-spp renders of every view, and the Chamfer and Hausdorff distances between the surfaces
(qsil_shape.SurfaceDistance: relative to Spot's bounding-box diagonal). Output (--out): loss.png
(loss and distances against time), views.png (target, start and each method's result for every
view), results.json (the record), report.md (the text --page writes into
docs/inverse-rendering.md).

Usage: /usr/bin/python3 examples/inverse_rendering.py [--build build] [--seconds 150] [--res 64]
       /usr/bin/python3 examples/inverse_rendering.py --page docs/inverse-rendering.md \
           --page-from docs/images/inverse-rendering/results.json
Needs the Python module (built by CMake into BUILD/python), NumPy, SciPy and matplotlib (Debian).
"""
import argparse
import math
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))  # qsil_shape: the source tree's, beside this script
from qsil_shape import (LargeSteps, Progress, SurfaceDistance, add_page_arguments, icosphere,  # noqa: E402
                        mean_edge, page_from_record, progress_chart, ratio, write_obj, write_record)
SCENE = os.path.join(ROOT, "scenes", "spot-mirror.xml")
RECORD = "images/inverse-rendering/results.json"
SCRIPT = "examples/inverse_rendering.py"


def rotation_y(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rotation_x(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def view_rotation(i, views):
    """View i: turned by 2 pi i / views about the vertical axis, tilted by +-30 degrees about x
    (alternating), so that the top and bottom are seen too."""
    return rotation_y(2 * math.pi * i / views) @ rotation_x(math.radians(30 if i % 2 == 0 else -30))


def page_text(r):
    """docs/inverse-rendering.md's generated section for this demo, from the record r (results.json)."""
    floor = r["floor"]
    pct = lambda x: "%.1f %%" % (100 * x)  # noqa: E731
    out = ["**Set-up** (from the record): %d views at %d², %d spp per step for the primal render and for the "
           "reverse run (independent seeds), targets at %d spp; start: a sphere of %d vertices; Large Steps λ %g, "
           "step %g on u, %d remeshings at equal shares of the time (half the mean edge, at least %g), the step "
           "×%g each. Each method runs %g s on %d threads. Scoring, outside the budget: the loss of fixed-seed "
           "64-spp renders of every view (its noise floor, Spot's own loss, is %.5f; the chart shows the loss above "
           "it) and the distances between the surfaces in %% of Spot's diagonal (%.2f)." % (
               r["views"], r["res"], r["spp"], r["target_spp"], r["start_vertices"], r["lam"], r["lr"],
               r["remeshes"], r["min_edge"], r["lr_decay"], r["seconds"], r["threads"], floor, r["diag"]),
           "",
           "| method | steps in %g s | steps/s | vertices | loss above floor | Chamfer | Hausdorff |" % r["seconds"],
           "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
           "| start (sphere) | | | %d | %.5f | %s | %s |" % (r["start_vertices"], r["start"]["loss"] - floor,
                                                          pct(r["start"]["chamfer"]), pct(r["start"]["hausdorff"]))]
    for name, m in r["methods"].items():
        out.append("| %s | %d | %.1f | %d | %.5f | %s | %s |" % (
            name, m["steps"], m["steps"] / max(r["seconds"], 1e-9), m["vertices"], m["loss"] - floor, pct(m["chamfer"]),
            pct(m["hausdorff"])))
    ms = r["methods"]
    if "quadric" in ms and "vsphere" in ms:
        q, v = ms["quadric"], ms["vsphere"]
        out += ["", "- quadric against vsphere at equal time: loss above the floor %.5f against %.5f (%s), "
                    "Chamfer %s against %s, Hausdorff %s against %s; the sphere started at %s and %s." % (
                        q["loss"] - floor, v["loss"] - floor, ratio(v["loss"] - floor, q["loss"] - floor),
                        pct(q["chamfer"]), pct(v["chamfer"]), pct(q["hausdorff"]), pct(v["hausdorff"]),
                        pct(r["start"]["chamfer"]), pct(r["start"]["hausdorff"]))]
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build directory with python/qsil*.so")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "inverse-rendering"))
    ap.add_argument("--seconds", type=float, default=150, help="optimisation wall time per method")
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=4, help="samples per pixel of each primal render and gradient")
    ap.add_argument("--target-spp", type=int, default=256)
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument("--subdiv", type=int, default=3, help="icosphere subdivisions of the start (3: 642 vertices)")
    ap.add_argument("--lr", type=float, default=0.02, help="Large Steps' step on u")
    ap.add_argument("--lam", type=float, default=19.0, help="lambda of (I + lambda L)")
    ap.add_argument("--remeshes", type=int, default=2, help="remeshings, at equal shares of the time")
    ap.add_argument("--lr-decay", type=float, default=0.7, help="step size factor at each remeshing")
    ap.add_argument("--min-edge", type=float, default=0.04, help="shortest target edge length of a remeshing")
    ap.add_argument("--methods", default="quadric,vsphere")
    ap.add_argument("--threads", type=int, default=0)
    add_page_arguments(ap)
    args = ap.parse_args()
    sys.path.insert(0, os.path.join(args.build, "python"))
    if page_from_record(ap, args, RECORD, SCRIPT, page_text):
        return
    import qsil  # noqa: E402  (built module)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(args.out, exist_ok=True)
    defines = {"res": str(args.res), "max_depth": "3"}
    rotations = [view_rotation(i, args.views) for i in range(args.views)]

    # ---- Targets: Spot turned to each angle (fixed seeds).
    truth_scene = qsil.Scene(SCENE, defines)
    TV, TF = truth_scene.vertices("spot"), truth_scene.triangles("spot").astype(np.int64)
    distances = SurfaceDistance(TV, TF)
    targets = []
    for i, R in enumerate(rotations):
        truth_scene.set_vertices("spot", TV @ R.T)
        targets.append(qsil.render(truth_scene, spp=args.target_spp, seed=1000 + i, threads=args.threads))

    def evaluate(V, F):
        """Fixed-seed evaluation loss (64 spp per view) and the images."""
        total, images = 0.0, []
        for i, R in enumerate(rotations):
            truth_scene.set_mesh("spot", V @ R.T, F)
            img = qsil.render(truth_scene, spp=64, seed=5000 + i, threads=args.threads)
            images.append(img)
            total += float(((img - targets[i]) ** 2).mean()) / len(rotations)
        return total, images

    # The noise floor: the evaluation loss of Spot itself (Monte Carlo noise of the targets and of
    # the evaluation renders); the chart shows the loss above it.
    floor, _ = evaluate(TV, TF)
    # ---- The start: a sphere around Spot's bounding-box centre.
    V0, F0 = icosphere(args.subdiv, 0.5 * (TV.min(axis=0) + TV.max(axis=0)), 0.55)
    start_loss, start_images = evaluate(V0, F0)
    start_chamfer, start_hausdorff = distances(V0, F0)
    results = {"res": args.res, "spp": args.spp, "target_spp": args.target_spp, "views": args.views,
               "start_vertices": int(len(V0)), "seconds": args.seconds, "lr": args.lr, "lam": args.lam,
               "remeshes": args.remeshes, "lr_decay": args.lr_decay, "min_edge": args.min_edge,
               "threads": args.threads or os.cpu_count(), "diag": distances.diag, "floor": floor,
               "start": {"loss": start_loss, "chamfer": start_chamfer, "hausdorff": start_hausdorff}, "methods": {}}
    finals = {}
    for method in args.methods.split(","):
        scenes = [qsil.Scene(SCENE, defines) for _ in rotations]

        def set_up(V, F):
            """Every view's scene holds the turned mesh; a new estimator per view."""
            for sc, R in zip(scenes, rotations):
                sc.set_mesh("spot", V @ R.T, F)
            return [qsil.ReverseEstimator(sc, ["spot"], boundary=method) for sc in scenes]

        V, F = V0.copy(), F0.copy()
        estimators = set_up(V, F)
        opt = LargeSteps(V, F, lam=args.lam, lr=args.lr)
        curve = [(0.0, 0, start_loss, start_chamfer, start_hausdorff, int(len(V)))]
        elapsed, step, seed = 0.0, 0, 1
        next_eval, next_remesh = 0.1 * args.seconds, args.seconds / (args.remeshes + 1)
        progress = Progress(method, args.seconds)
        while elapsed < args.seconds:
            t0 = time.perf_counter()
            grad = np.zeros_like(V)
            step_loss = 0.0
            for sc, est, R, target in zip(scenes, estimators, rotations, targets):
                image = est.render(spp=args.spp, seed=seed, threads=args.threads)
                step_loss += float(((image - target) ** 2).mean()) / len(scenes)
                w = 2 * (image - target) / (image.size * len(scenes))
                g = est.run(w, spp=args.spp, seed=seed + 1, threads=args.threads)["gradient"]["spot"]
                grad += g @ R  # back to the unturned frame: R^T g, row-wise
                seed += 2
            V = opt.step(grad)
            step += 1
            if elapsed >= next_remesh and next_remesh < args.seconds:
                V, F = qsil.remesh(V, F, max(0.5 * mean_edge(V, F), args.min_edge))
                F = F.astype(np.int64)
                opt = opt.remeshed(V, F, lr_scale=args.lr_decay)
                estimators = set_up(V, F)
                next_remesh += args.seconds / (args.remeshes + 1)
            else:
                for sc, est, R in zip(scenes, estimators, rotations):
                    sc.set_vertices("spot", V @ R.T)
                    est.update()
            elapsed += time.perf_counter() - t0
            progress.show(elapsed, step, step_loss)
            if elapsed >= next_eval or elapsed >= args.seconds:
                loss, _ = evaluate(V, F)
                chamfer, hausdorff = distances(V, F)
                curve.append((elapsed, step, loss, chamfer, hausdorff, int(len(V))))
                progress.clear()
                print("%-8s %6.1f s  step %4d (%.2f/s)  loss %.5f (floor %.5f)  chamfer %.2f %%  hausdorff %.2f %%  "
                      "%d vertices" % (method, elapsed, step, step / elapsed, loss, floor, 100 * chamfer,
                                       100 * hausdorff, len(V)), flush=True)
                next_eval += 0.1 * args.seconds
        progress.clear()
        loss, images = evaluate(V, F)
        finals[method] = images
        _, _, _, chamfer, hausdorff, nv = curve[-1]
        results["methods"][method] = {"steps": step, "loss": loss, "chamfer": chamfer, "hausdorff": hausdorff,
                                      "vertices": nv, "curve": curve}
        write_obj(os.path.join(args.out, "result-%s.obj" % method), V, F)

    # ---- Charts: loss above the floor and distances against time; the views.
    progress_chart(os.path.join(args.out, "loss.png"), results["methods"], floor,
                   "Shape from mirror reflections: %d views, %d^2, %d spp per step" % (args.views, args.res, args.spp))
    rows = [("target", targets), ("start", start_images)] + [(m, finals[m]) for m in finals]
    fig, axes = plt.subplots(len(rows), len(rotations), figsize=(2 * len(rotations), 2 * len(rows)), squeeze=False)
    for r, (name, imgs) in enumerate(rows):
        for c, img in enumerate(imgs):
            a = axes[r][c]
            a.imshow(np.clip(img, 0, 1) ** (1 / 2.2))
            a.set_xticks([])
            a.set_yticks([])
            if c == 0:
                a.set_ylabel(name)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "views.png"), dpi=100)
    plt.close(fig)
    write_record(args, results, RECORD, SCRIPT, page_text)


if __name__ == "__main__":
    main()
