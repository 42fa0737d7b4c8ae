#!/usr/bin/env python3
"""Reconstruct an object seen only in two rough mirrors ([QSS] Sec. 5.5, Fig. 14) with qsil's reverse mode.

The scene is scenes/two-mirrors.xml: the camera sees the bunny, which stands behind it, only in two
GGX mirrors (alpha 0.01) set in a shallow V, each showing it from its own side, under an
environment map. One target image (the true bunny, high spp); the optimisation starts from a
sphere and moves every vertex:

    loss  = mean over pixel-channels of (I - T)^2
    dL/dx = ReverseEstimator.run(adjoint = 2 (I - T) / n), I from a primal render with its own
            seed (the product of two independent estimates is unbiased)
    step  = qsil_shape.LargeSteps: uniform Adam on u = (I + lam L) x (Nicolet et al. 2021)
    remesh: at equal shares of the time, qsil.remesh (CGAL isotropic remeshing) to half the mean
            edge length, the step size times --lr-decay, the Adam moments reset

The estimator is set up once per mesh (qsil.ReverseEstimator: update() refits the edge forest after
each step, sets up anew after a remeshing). Each boundary method (quadric: the edge forest;
vsphere: Li 2019's tree; none: no boundary term) runs for the same wall time; METHOD:2 also fits
the image of a second camera that sees the object directly (a multi-view target, for
comparison). At ten points the shape is scored outside the budget: the loss of a fixed-seed
render from the camera, and the Chamfer and
Hausdorff distances to the true mesh (area-uniform surface samples, relative to the true mesh's
bounding-box diagonal). Output (--out): results.json (the record), progress.png (loss and
distances against time), evolution-METHOD.png (the shape at five times, from the camera and from
a second camera that sees the object directly), report.md (the table docs/inverse-rendering.md
quotes).

Usage: /usr/bin/python3 examples/two_mirrors.py [--build build] [--seconds 1200] [--methods quadric,vsphere,none]
Needs the Python module (built by CMake into BUILD/python), NumPy, SciPy and matplotlib (Debian).
"""
import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np
from scipy.spatial import cKDTree

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "scenes", "two-mirrors.xml")
# The second camera (display only): beside the bunny, looking at its bounding-box centre.
SECOND_VIEW = '<lookat origin="1.7, 0.9, 3.3" target="0, 0, 1.4" up="0, 1, 0"/>'


def second_view_scene(tmp):
    """two-mirrors.xml seen by the second camera (absolute paths, written to tmp)."""
    with open(SCENE) as f:
        xml = f.read()
    xml = xml.replace('<lookat origin="0, 0, 0" target="0, 0, -1" up="0, 1, 0"/>', SECOND_VIEW)
    scenes = os.path.join(ROOT, "scenes")
    xml = xml.replace('value="meshes/', 'value="%s/meshes/' % scenes).replace('value="envmaps/', 'value="%s/envmaps/' % scenes)
    path = os.path.join(tmp, "two-mirrors-second-view.xml")
    with open(path, "w") as f:
        f.write(xml)
    return path


def surface_samples(V, F, n, rng):
    """n points uniform by area on the triangles F of V."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    tri = rng.choice(len(F), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    return (1 - s)[:, None] * a[tri] + (s * (1 - r2))[:, None] * b[tri] + (s * r2)[:, None] * c[tri]


def distances(V, F, truth_points, truth_tree, diag, n=20000):
    """Chamfer (mean of both directions' mean nearest distance) and Hausdorff distance between the
    surfaces, from n area-uniform samples each, relative to diag (fixed seed)."""
    pts = surface_samples(V, F, n, np.random.default_rng(7))
    d_to_truth, _ = truth_tree.query(pts)
    d_from_truth, _ = cKDTree(pts).query(truth_points)
    chamfer = 0.5 * (d_to_truth.mean() + d_from_truth.mean())
    return chamfer / diag, max(d_to_truth.max(), d_from_truth.max()) / diag


def mean_edge(V, F):
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return float(np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1).mean())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build directory with python/qsil*.so")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "two-mirrors"))
    ap.add_argument("--seconds", type=float, default=1200, help="optimisation wall time per method")
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=4, help="samples per pixel of each primal render and gradient")
    ap.add_argument("--target-spp", type=int, default=1024)
    ap.add_argument("--subdiv", type=int, default=3, help="icosphere subdivisions of the start (3: 642 vertices)")
    ap.add_argument("--radius", type=float, default=0.6, help="radius of the start sphere (scene units)")
    ap.add_argument("--lr", type=float, default=1e-2, help="Large Steps' step on u")
    ap.add_argument("--lam", type=float, default=19.0, help="lambda of (I + lambda L)")
    ap.add_argument("--remeshes", type=int, default=3, help="remeshings, at equal shares of the time")
    ap.add_argument("--lr-decay", type=float, default=0.7, help="step size factor at each remeshing")
    ap.add_argument("--min-edge", type=float, default=0.035, help="shortest target edge length of a remeshing")
    ap.add_argument("--methods", default="quadric,vsphere,none,quadric:2",
                    help="boundary methods to compare; METHOD:2 also fits the second camera's image (two targets)")
    ap.add_argument("--threads", type=int, default=0)
    args = ap.parse_args()
    sys.path.insert(0, os.path.join(args.build, "python"))
    import qsil  # noqa: E402  (built module)
    from qsil_shape import LargeSteps, icosphere  # noqa: E402  (python/, copied beside it)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(args.out, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="qsil-two-mirrors-")
    defines = {"res": str(args.res), "max_depth": "3"}

    # ---- The truth and the target image (fixed seed).
    truth_scene = qsil.Scene(SCENE, defines)
    TV, TF = truth_scene.vertices("bunny"), truth_scene.triangles("bunny").astype(np.int64)
    target = qsil.render(truth_scene, spp=args.target_spp, seed=1, threads=args.threads)
    diag = float(np.linalg.norm(TV.max(axis=0) - TV.min(axis=0)))
    truth_points = surface_samples(TV, TF, 20000, np.random.default_rng(3))
    truth_tree = cKDTree(truth_points)
    second_xml = second_view_scene(tmp)
    second = qsil.Scene(second_xml, defines)
    second_target = qsil.render(second, spp=args.target_spp, seed=2, threads=args.threads)

    def pictures(V, F):
        """The mesh from the camera and from the second camera (64 spp, fixed seeds)."""
        truth_scene.set_mesh("bunny", V, F)
        second.set_mesh("bunny", V, F)
        return (qsil.render(truth_scene, spp=64, seed=11, threads=args.threads),
                qsil.render(second, spp=64, seed=12, threads=args.threads))

    truth_pictures = pictures(TV, TF)
    # The noise floor of the scoring: the loss of the true mesh's fixed-seed render.
    truth_scene.set_mesh("bunny", TV, TF)
    floor = float(((qsil.render(truth_scene, spp=64, seed=5, threads=args.threads) - target) ** 2).mean())

    centre = 0.5 * (TV.min(axis=0) + TV.max(axis=0))
    V0, F0 = icosphere(args.subdiv, centre, args.radius)
    F0 = F0.astype(np.int64)
    start_chamfer, start_hausdorff = distances(V0, F0, truth_points, truth_tree, diag)
    results = {"res": args.res, "spp": args.spp, "target_spp": args.target_spp, "seconds": args.seconds,
               "lr": args.lr, "lam": args.lam, "remeshes": args.remeshes, "lr_decay": args.lr_decay,
               "start_vertices": int(len(V0)), "truth_vertices": int(len(TV)), "diag": diag, "floor": floor,
               "methods": {}}
    evolution = {}
    for name in args.methods.split(","):
        method, _, views = name.partition(":")
        # The camera's scene, and with METHOD:2 the second camera's: one target and estimator each.
        scenes = [qsil.Scene(SCENE, defines)] + ([qsil.Scene(second_xml, defines)] if views == "2" else [])
        targets = [target, second_target][:len(scenes)]
        for sc in scenes:
            sc.set_mesh("bunny", V0, F0)
        scene = scenes[0]
        V, F = V0.copy(), F0.copy()
        opt = LargeSteps(V, F, lam=args.lam, lr=args.lr)
        estimators = [qsil.ReverseEstimator(sc, ["bunny"], boundary=method) for sc in scenes]

        def score():
            """The loss of the scene's current mesh, rendered at a fixed seed (64 spp)."""
            img = qsil.render(scene, spp=64, seed=5, threads=args.threads)
            return float(((img - target) ** 2).mean())

        loss0 = score()
        curve = [(0.0, 0, loss0, start_chamfer, start_hausdorff, int(len(V)))]
        snapshots = [(0.0, pictures(V, F))]
        elapsed, step, seed, refits, setups = 0.0, 0, 100, 0, 0
        next_eval, next_remesh, next_picture = 0.1 * args.seconds, args.seconds / (args.remeshes + 1), 0.25
        while elapsed < args.seconds:
            t0 = time.perf_counter()
            grad = np.zeros_like(V)
            for sc, est, tgt in zip(scenes, estimators, targets):
                image = qsil.render(sc, spp=args.spp, seed=seed, threads=args.threads)
                w = 2 * (image - tgt) / (image.size * len(scenes))
                grad += est.run(w, spp=args.spp, seed=seed + 1, threads=args.threads)["gradient"]["bunny"]
                seed += 2
            V = opt.step(grad)
            step += 1
            if elapsed >= next_remesh and next_remesh < args.seconds:
                length = max(0.5 * mean_edge(V, F), args.min_edge)
                V, F = qsil.remesh(V, F, length)
                F = F.astype(np.int64)
                opt = opt.remeshed(V, F, lr_scale=args.lr_decay)
                for sc in scenes:
                    sc.set_mesh("bunny", V, F)
                next_remesh += args.seconds / (args.remeshes + 1)
            else:
                for sc in scenes:
                    sc.set_vertices("bunny", V)
            for est in estimators:
                u = est.update()
                refits += bool(u["refitted"])
                setups += not u["refitted"] and u["reason"] != "no boundary term"
            elapsed += time.perf_counter() - t0
            if elapsed >= next_eval or elapsed >= args.seconds:
                loss = score()
                chamfer, hausdorff = distances(V, F, truth_points, truth_tree, diag)
                curve.append((elapsed, step, loss, chamfer, hausdorff, int(len(V))))
                print("%-8s %7.1f s  step %5d (%.2f/s)  loss %.5f (floor %.5f)  chamfer %.2f %%  hausdorff %.2f %%  "
                      "%d vertices" % (name, elapsed, step, step / elapsed, loss, floor, 100 * chamfer,
                                       100 * hausdorff, len(V)), flush=True)
                next_eval += 0.1 * args.seconds
            if elapsed >= next_picture * args.seconds or elapsed >= args.seconds:
                snapshots.append((elapsed, pictures(V, F)))
                next_picture += 0.25
        t, s, loss, chamfer, hausdorff, nv = curve[-1]
        results["methods"][name] = {"steps": step, "loss": loss, "chamfer": chamfer, "hausdorff": hausdorff,
                                      "vertices": nv, "refits": refits, "setups": setups, "curve": curve}
        evolution[name] = snapshots
        with open(os.path.join(args.out, "result-%s.obj" % name.replace(":", "-")), "w") as out:
            out.writelines("v %.9g %.9g %.9g\n" % tuple(p) for p in V)
            out.writelines("f %d %d %d\n" % tuple(f + 1) for f in F)

    # ---- Charts: loss above the floor, Chamfer and Hausdorff against time.
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for method, r in results["methods"].items():
        c = np.array(r["curve"])
        label = "%s (%d steps)" % (method, r["steps"])
        axes[0].plot(c[:, 0], np.maximum(c[:, 2] - floor, 1e-9), marker="o", label=label)
        axes[1].plot(c[:, 0], 100 * c[:, 3], marker="o", label=label)
        axes[2].plot(c[:, 0], 100 * c[:, 4], marker="o", label=label)
    axes[0].set_yscale("log")
    axes[0].set_ylabel("image loss above the noise floor (%.2g)" % floor)
    axes[1].axhline(1.0, color="k", ls="--", lw=0.8)
    axes[1].set_ylabel("Chamfer distance (% of the diagonal)")
    axes[2].axhline(5.0, color="k", ls="--", lw=0.8)
    axes[2].set_ylabel("Hausdorff distance (% of the diagonal)")
    for a in axes:
        a.set_xlabel("optimisation time (s, 2 threads)")
        a.legend()
    fig.suptitle("Two mirrors: %d^2, %d spp per step, %d remeshings" % (args.res, args.spp, args.remeshes))
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "progress.png"), dpi=110)
    plt.close(fig)
    for method, snapshots in evolution.items():
        cols = [("truth", truth_pictures)] + [("%.0f s" % t, p) for t, p in snapshots]
        fig, axes = plt.subplots(2, len(cols), figsize=(2.2 * len(cols), 4.6))
        for c, (name, (a, b)) in enumerate(cols):
            for r, img in enumerate((a, b)):
                axes[r][c].imshow(np.clip(img, 0, 1) ** (1 / 2.2))
                axes[r][c].set_xticks([])
                axes[r][c].set_yticks([])
            axes[0][c].set_title(name)
        axes[0][0].set_ylabel("camera (mirrors)")
        axes[1][0].set_ylabel("second camera")
        fig.suptitle(method)
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, "evolution-%s.png" % method.replace(":", "-")), dpi=100)
        plt.close(fig)
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    lines = ["| method | steps | set-ups / refits | vertices | loss | Chamfer | Hausdorff |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
             "| start | | | %d | %.5f | %.2f %% | %.2f %% |" % (len(V0), results["methods"][next(iter(results["methods"]))]
                                                               ["curve"][0][2], 100 * start_chamfer,
                                                               100 * start_hausdorff)]
    for method, r in results["methods"].items():
        lines.append("| %s | %d | %d / %d | %d | %.5f | %.2f %% | %.2f %% |" % (
            method, r["steps"], r["setups"], r["refits"], r["vertices"], r["loss"], 100 * r["chamfer"],
            100 * r["hausdorff"]))
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    print("noise floor %.5f -> %s" % (floor, args.out))


if __name__ == "__main__":
    main()
