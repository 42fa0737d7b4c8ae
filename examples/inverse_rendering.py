#!/usr/bin/env python3
"""Recover a shape from images of its reflection ([QSS] Sec. 5.5 style), with qsil's reverse mode.

The scene is scenes/spot-mirror.xml: the camera sees the object ONLY in a rough GGX mirror
(alpha 0.01) under an environment map, so the object's outline in the images moves only through
the secondary boundary term (silhouettes seen from points on the mirror). Targets: renders of
Spot turned to four angles about the vertical axis and tilted by +-30 degrees (the object is
turned, not the camera: view i sets the vertices to R_i x and turns the gradient back with R_i^T). The optimisation starts from
a sphere and moves every vertex:

    loss  = mean over views and pixel-channels of (I - T)^2
    dL/dx = qsil.reverse(adjoint = 2 (I - T) / n), I from a primal render with its own seed
            (so the product of the two estimates is unbiased)
    step  = Adam on u = (I + lambda L) x, x = (I + lambda L)^-1 u  (Nicolet et al. 2021, "Large
            Steps in Inverse Rendering of Geometry"; L the combinatorial Laplacian, SciPy's
            sparse LU factorised once)

Each boundary method (quadric: the edge forest; vsphere: Li 2019's tree) runs for the same wall
time; every few steps the current shape is scored with a fixed-seed, high-spp evaluation (not
counted in the budget). Output (--out): loss.png (evaluation loss against optimisation time),
views.png (target, start and each method's result for every view), results.json (losses,
steps, Chamfer and Hausdorff distances to Spot's vertices).

Usage: /usr/bin/python3 examples/inverse_rendering.py [--build build] [--seconds 120] [--res 64]
Needs the Python module (built by CMake into BUILD/python), NumPy, SciPy and matplotlib (Debian).
"""
import argparse
import json
import math
import os
import sys
import tempfile
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def write_obj(path, vertices, triangles):
    with open(path, "w") as out:
        for p in vertices:
            out.write("v %.9g %.9g %.9g\n" % tuple(p))
        for a, b, c in triangles:
            out.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))


def scene_with_mesh(obj_path, tmp):
    """spot-mirror.xml with the object's mesh replaced (absolute paths, written to tmp)."""
    scenes = os.path.join(ROOT, "scenes")
    with open(os.path.join(scenes, "spot-mirror.xml")) as f:
        xml = f.read()
    xml = xml.replace('value="meshes/spot.obj"', 'value="%s"' % obj_path)
    xml = xml.replace('value="envmaps/forest.exr"', 'value="%s"' % os.path.join(scenes, "envmaps", "forest.exr"))
    path = os.path.join(tmp, "scene-%s.xml" % os.path.basename(obj_path))
    with open(path, "w") as f:
        f.write(xml)
    return path


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


def distances(a, b):
    """Chamfer (mean of both directions' mean nearest distance) and Hausdorff distance."""
    da, _ = cKDTree(b).query(a)
    db, _ = cKDTree(a).query(b)
    return 0.5 * (da.mean() + db.mean()), max(da.max(), db.max())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build directory with python/qsil*.so")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "inverse-rendering"))
    ap.add_argument("--seconds", type=float, default=120, help="optimisation wall time per method")
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=4, help="samples per pixel of each gradient")
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument("--subdiv", type=int, default=3, help="icosphere subdivisions of the start (3: 642 vertices)")
    ap.add_argument("--lr", type=float, default=0.02, help="Adam step on u")
    ap.add_argument("--smooth", type=float, default=20.0, help="lambda of (I + lambda L)")
    ap.add_argument("--methods", default="quadric,vsphere")
    ap.add_argument("--threads", type=int, default=0)
    args = ap.parse_args()
    sys.path.insert(0, os.path.join(args.build, "python"))
    import qsil  # noqa: E402  (built module)
    from qsil_shape import combinatorial_laplacian, icosphere  # noqa: E402  (python/, copied beside it)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(args.out, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="qsil-inverse-")
    defines = {"res": str(args.res), "max_depth": "3"}
    rotations = [view_rotation(i, args.views) for i in range(args.views)]

    # ---- Targets: Spot turned to each angle (256 spp, fixed seeds).
    truth_scene = qsil.Scene(os.path.join(ROOT, "scenes", "spot-mirror.xml"), defines)
    truth = truth_scene.vertices("spot")
    targets = []
    for i, R in enumerate(rotations):
        truth_scene.set_vertices("spot", truth @ R.T)
        targets.append(qsil.render(truth_scene, spp=256, seed=1000 + i, threads=args.threads))

    # ---- The start: a sphere around Spot's bounding-box centre.
    centre = 0.5 * (truth.min(axis=0) + truth.max(axis=0))
    sv, sf = icosphere(args.subdiv, centre, 0.55)
    obj = os.path.join(tmp, "sphere.obj")
    write_obj(obj, sv, sf)
    scene = qsil.Scene(scene_with_mesh(obj, tmp), defines)
    x0 = scene.vertices("spot")
    tris = scene.triangles("spot")
    n = len(x0)
    solve = spla.factorized((sp.identity(n) + args.smooth * combinatorial_laplacian(tris, n)).tocsc())
    M = (sp.identity(n) + args.smooth * combinatorial_laplacian(tris, n)).tocsr()

    def evaluate(x):
        """Fixed-seed evaluation loss (64 spp per view) and the images."""
        total, images = 0.0, []
        for i, R in enumerate(rotations):
            scene.set_vertices("spot", x @ R.T)
            img = qsil.render(scene, spp=64, seed=5000 + i, threads=args.threads)
            images.append(img)
            total += float(((img - targets[i]) ** 2).mean()) / len(rotations)
        return total, images

    # The noise floor: the evaluation loss of Spot itself (Monte Carlo noise of the target and of
    # the evaluation renders); the chart shows the loss above it.
    floor = 0.0
    for i, R in enumerate(rotations):
        truth_scene.set_vertices("spot", truth @ R.T)
        img = qsil.render(truth_scene, spp=64, seed=5000 + i, threads=args.threads)
        floor += float(((img - targets[i]) ** 2).mean()) / len(rotations)
    start_loss, start_images = evaluate(x0)
    results = {"res": args.res, "spp": args.spp, "views": args.views, "vertices": int(n),
               "seconds": args.seconds, "floor": floor, "start": {"loss": start_loss}, "methods": {}}
    results["start"]["chamfer"], results["start"]["hausdorff"] = distances(x0, truth)
    finals = {}
    for method in args.methods.split(","):
        u = M @ x0
        m1, m2 = np.zeros_like(u), np.zeros_like(u)
        b1, b2 = 0.9, 0.999
        curve = [(0.0, start_loss)]
        elapsed, step, seed = 0.0, 0, 1
        next_eval = 0.1 * args.seconds
        while elapsed < args.seconds:
            t0 = time.perf_counter()
            x = solve(u)
            grad = np.zeros_like(x)
            for i, R in enumerate(rotations):
                scene.set_vertices("spot", x @ R.T)
                image = qsil.render(scene, spp=args.spp, seed=seed, threads=args.threads)
                w = 2 * (image - targets[i]) / (image.size * len(rotations))
                r = qsil.reverse(scene, ["spot"], w, spp=args.spp, seed=seed + 1, threads=args.threads,
                                 boundary=method)
                grad += r["gradient"]["spot"] @ R  # back to the unturned frame: R^T g, row-wise
                seed += 2
            gu = solve(grad)  # (I + lambda L) is symmetric: its inverse transpose is its inverse
            step += 1
            m1 = b1 * m1 + (1 - b1) * gu
            m2 = b2 * m2 + (1 - b2) * gu * gu
            u = u - args.lr * (m1 / (1 - b1 ** step)) / (np.sqrt(m2 / (1 - b2 ** step)) + 1e-8)
            elapsed += time.perf_counter() - t0
            if elapsed >= next_eval or elapsed >= args.seconds:
                loss, _ = evaluate(solve(u))
                curve.append((elapsed, loss))
                print("%-8s %6.1f s  step %4d  loss %.5f" % (method, elapsed, step, loss), flush=True)
                next_eval += 0.1 * args.seconds
        x = solve(u)
        loss, images = evaluate(x)
        chamfer, hausdorff = distances(x, truth)
        finals[method] = images
        results["methods"][method] = {"steps": step, "loss": loss, "chamfer": chamfer, "hausdorff": hausdorff,
                                      "curve": curve}
        write_obj(os.path.join(args.out, "result-%s.obj" % method), x, tris)

    # ---- Charts.
    fig, ax = plt.subplots(figsize=(6, 4))
    for method, r in results["methods"].items():
        t, l = zip(*r["curve"])
        ax.plot(t, np.maximum(np.array(l) - floor, 1e-9), marker="o", label="%s (%d steps)" % (method, r["steps"]))
    ax.set_xlabel("optimisation time (s, 2 threads)")
    ax.set_ylabel("image loss above the noise floor (%.4f)" % floor)
    ax.set_yscale("log")
    ax.legend()
    ax.set_title("Shape from mirror reflections: %d views, %d^2, %d spp" % (args.views, args.res, args.spp))
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "loss.png"), dpi=120)
    rows = [("target", targets), ("start", start_images)] + [(m, finals[m]) for m in finals]
    fig, axes = plt.subplots(len(rows), len(rotations), figsize=(2 * len(rotations), 2 * len(rows)))
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
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    for method, r in results["methods"].items():
        print("%-8s steps %4d  loss %.5f  chamfer %.4f  hausdorff %.4f" % (method, r["steps"], r["loss"],
                                                                           r["chamfer"], r["hausdorff"]))
    print("start    loss %.5f  chamfer %.4f  hausdorff %.4f  (noise floor %.5f) -> %s" % (
        start_loss, results["start"]["chamfer"], results["start"]["hausdorff"], floor, args.out))


if __name__ == "__main__":
    main()
