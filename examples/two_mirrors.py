#!/usr/bin/env python3
"""Reconstruct an object whose details are seen only in two rough mirrors ([QSS] Sec. 5.5, Fig. 14) with qsil's reverse mode.

The scene is scenes/two-mirrors.xml: the camera sees the bunny directly from behind, and its face
and flanks only in two GGX mirrors (alpha 0.01) behind it, one on each side, under an environment
map. One target image (the true bunny, high spp; one per film size of --res, which
grows at each remeshing: coarse to fine); the optimisation starts from a sphere and moves every
vertex:

    loss  = mean over pixel-channels of (I - T)^2
    dL/dx = ReverseEstimator.run(adjoint = 2 (I - T) / n), I = ReverseEstimator.render with its own
            seed (the product of two independent estimates is unbiased)
    step  = qsil_shape.LargeSteps: uniform Adam on u = (I + lam L) x (Nicolet et al. 2021)
    remesh: at equal shares of the time, qsil.remesh (CGAL isotropic remeshing) to half the mean
            edge length, the step size times --lr-decay, the Adam moments reset

The estimator is set up once per mesh (qsil.ReverseEstimator: update() refits the edge forest after
each step, sets up anew after a remeshing). Each boundary method (quadric: the edge forest;
vsphere: Li 2019's tree; none: no boundary term) runs for the same wall time; METHOD:2 also fits
the image of a second camera that sees the object from its side (a multi-view target, for
comparison). At ten points the shape is scored outside the budget: the loss of a fixed-seed
render from the camera at the largest film size, and the Chamfer and Hausdorff distances to the
true mesh (qsil_shape.SurfaceDistance: area-uniform surface samples, relative to the true mesh's
bounding-box diagonal), of the whole surface and of the part the camera sees, directly or in a
mirror (seen_by_camera). On a terminal a status line shows the time budget, steps/s and the loss.
Output (--out): results.json (the record), progress.png (loss and distances against time),
evolution-METHOD.png (the shape at five times, from the camera and from a second camera that sees
the object from its side), report.md (the text that --page writes into docs/inverse-rendering.md;
--page-from rewrites it from a record alone).

Usage: /usr/bin/python3 examples/two_mirrors.py [--build build] [--seconds 1200] [--methods quadric,vsphere,none]
Needs the Python module (built by CMake into BUILD/python), NumPy, SciPy and matplotlib (Debian).
"""
import argparse
import os
import re
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))  # qsil_shape: the source tree's, beside this script
from qsil_shape import (LargeSteps, Progress, SurfaceDistance, add_page_arguments, icosphere,  # noqa: E402
                        mean_edge, page_from_record, progress_chart, ratio, write_obj, write_record)
SCENE = os.path.join(ROOT, "scenes", "two-mirrors.xml")
# The second camera (display only): beside the bunny, looking at its bounding-box centre.
SECOND_VIEW = '<lookat origin="3.2, 1.6, -2.6" target="0, 0, -3.4" up="0, 1, 0"/>'


def camera_lookat(xml, where):
    """The text of the first <lookat .../> element of a scene's XML text (the camera's); where names
    the file in the error (ValueError) when there is none."""
    m = re.search(r"<lookat [^>]*/>", xml)
    if m is None:
        raise ValueError("%s: no <lookat .../> element for the camera" % where)
    return m.group(0)


def camera_half_fov(xml, where):
    """Half the camera's field of view in radians, from the first <float name="fov"> of a scene's XML
    text: the film is square, so the x and y fields of view are equal. ValueError (naming where)
    without one."""
    m = re.search(r'<float name="fov" value="([^"]*)"/>', xml)
    if m is None:
        raise ValueError("%s: no <float name=\"fov\" .../> for the camera" % where)
    return np.radians(0.5 * float(m.group(1)))


def second_view_scene(tmp):
    """two-mirrors.xml seen by the second camera (absolute paths, written to tmp)."""
    with open(SCENE) as f:
        xml = f.read()
    xml = xml.replace(camera_lookat(xml, SCENE), SECOND_VIEW)
    scenes = os.path.join(ROOT, "scenes")
    xml = xml.replace('value="meshes/', 'value="%s/meshes/' % scenes).replace('value="envmaps/', 'value="%s/envmaps/' % scenes)
    path = os.path.join(tmp, "two-mirrors-second-view.xml")
    with open(path, "w") as f:
        f.write(xml)
    return path


RECORD = "images/two-mirrors/results.json"
SCRIPT = "examples/two_mirrors.py"


def seen_how(r):
    """How the record r's "seen" part was seen, and by which function: records written before the
    scene changed (2026-11-27; no "mirror_only_share") scored the part seen in the mirrors, with
    seen_in_mirrors; later ones the part seen directly or in a mirror, with seen_by_camera."""
    if "mirror_only_share" not in r:
        return " in the mirrors", "", "seen_in_mirrors"
    return ", directly or in a mirror", "%.0f %% only in a mirror; " % (100 * r["mirror_only_share"]), "seen_by_camera"


def page_text(r):
    """docs/inverse-rendering.md's generated section for the two-mirror experiment: the set-up, the
    table and the comparisons, all from the record r (results.json)."""
    floor = r["floor"]
    pct = lambda x: "%.2f %%" % (100 * x)  # noqa: E731
    def sci(x):
        """x as 2.1·10⁻⁵ (nan and inf as themselves)."""
        if not np.isfinite(x):
            return str(x)
        mantissa, exponent = ("%.1e" % x).split("e")
        return "%s·10%s" % (mantissa, str(int(exponent)).translate(str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")))
    def loss_ratio(a, b, of=""):
        """ratio's text for two losses above the floor (followed by of), or why there is none: a
        loss at or below the floor is within the scoring render's noise, which cannot rank it."""
        if a > 0 and b > 0:
            return ratio(a, b) + of
        return "no ratio: a loss at or below the floor is within the scoring render's noise"
    res = r["res"]
    spp = r["spp"] if isinstance(r["spp"], list) else [r["spp"]]
    spp_text = " → ".join("%d" % x for x in spp) if len(set(spp)) > 1 else "%d" % spp[0]
    schedule = " → ".join("%d²" % x for x in res) if len(set(res)) > 1 else "%d²" % res[0]
    out = ["**Set-up** (from the record): film %s over %d phases of equal time between %d remeshings; %s spp "
           "per step for the primal render and for the reverse run (independent seeds); targets at %d spp; "
           "start: a sphere of %d vertices at the bunny's bounding-box centre; Large Steps λ %g, step %g on u, "
           "×%g at each remeshing (`qsil.remesh` to half the mean edge, at least %g: %.1f %% of the diagonal). "
           "Each method runs %g s on %d threads. At ten points the shape is scored outside the budget: the loss "
           "of a fixed-seed 64-spp render at %d² (its noise floor, the true bunny's loss, is %.5f) and the Chamfer "
           "and Hausdorff distances between the surfaces (20 000 area-uniform samples each), in %% of the bunny's "
           "diagonal (%.2f); \"seen\": the same distances between the %.0f %% of the bunny's surface that the camera "
           "sees%s (%sa ray test from each sample, `%s`) and the shape's samples nearest to it."
           % ((schedule, len(res), r["remeshes"], spp_text, r["target_spp"], r["start_vertices"],
               r["lam"], r["lr"], r["lr_decay"], r["min_edge"], 100 * r["min_edge"] / r["diag"],
               r["seconds"], r["threads"], r["score_res"], floor, r["diag"], 100 * r["seen_share"]) + seen_how(r)),
           "",
           "| method | steps in %g s | steps/s | set-ups / refits | vertices | loss above floor | Chamfer | Hausdorff "
           "| Chamfer, seen | Hausdorff, seen |" % r["seconds"],
           "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
           "| start (sphere) | | | | %d | %s | %s | %s | %s | %s |" % (
               r["start_vertices"], sci(r["start"]["loss"] - floor), pct(r["start"]["chamfer"]),
               pct(r["start"]["hausdorff"]), pct(r["start"]["seen_chamfer"]), pct(r["start"]["seen_hausdorff"]))]
    names = {"none": "none (no boundary term)"}
    for name, m in r["methods"].items():
        label = names.get(name, name + (" (two targets)" if name.endswith(":2") else ""))
        out.append("| %s | %d | %.1f | %d / %d | %d | %s | %s | %s | %s | %s |" % (
            label, m["steps"], m["steps"] / max(r["seconds"], 1e-9), m["setups"], m["refits"], m["vertices"],
            sci(m["loss"] - floor), pct(m["chamfer"]), pct(m["hausdorff"]), pct(m["seen_chamfer"]),
            pct(m["seen_hausdorff"])))
    ms = r["methods"]
    out.append("")
    if "quadric" in ms:
        q = ms["quadric"]
        met = q["chamfer"] <= 0.01 and q["hausdorff"] <= 0.05
        out.append("- Targets (Chamfer ≤ 1 %%, Hausdorff ≤ 5 %%, within 20 minutes): **%s** by quadric in this "
                   "record's %g s (%s, %s; on the seen part %s, %s)." % (
                       "met" if met else "not met", r["seconds"], pct(q["chamfer"]), pct(q["hausdorff"]),
                       pct(q["seen_chamfer"]), pct(q["seen_hausdorff"])))
        if "vsphere" in ms:
            v = ms["vsphere"]
            out.append("- quadric against vsphere at equal time: loss above the floor %s against %s (%s), Chamfer "
                       "%s against %s, Hausdorff %s against %s." % (
                           sci(q["loss"] - floor), sci(v["loss"] - floor),
                           loss_ratio(v["loss"] - floor, q["loss"] - floor), pct(q["chamfer"]), pct(v["chamfer"]),
                           pct(q["hausdorff"]), pct(v["hausdorff"])))
        if "none" in ms:
            n = ms["none"]
            out.append("- Without the boundary term (none): Chamfer %s (%s quadric's; the start's is %s), "
                       "Hausdorff %s, loss above the floor %s (%s)." % (
                           pct(n["chamfer"]), ratio(n["chamfer"], q["chamfer"]), pct(r["start"]["chamfer"]),
                           pct(n["hausdorff"]), sci(n["loss"] - floor),
                           loss_ratio(n["loss"] - floor, q["loss"] - floor, " quadric's")))
    return "\n".join(out) + "\n"


def occluded(origins, targets, V, F, chunk=128):
    """(k,) bool: whether the segment from each origin (k, 3) to its target (k, 3) crosses a
    triangle of V, F (Moller-Trumbore over all triangles; the ends excluded by 1e-6 of the length)."""
    a = V[F[:, 0]]
    e1, e2 = V[F[:, 1]] - a, V[F[:, 2]] - a
    hit = np.zeros(len(origins), dtype=bool)
    for i in range(0, len(origins), chunk):
        o, d = origins[i:i + chunk, None, :], (targets - origins)[i:i + chunk, None, :]
        pvec = np.cross(d, e2)
        det = np.einsum("ktj,tj->kt", pvec, e1)
        inv = 1.0 / np.where(np.abs(det) > 1e-300, det, 1e-300)
        tvec = o - a
        u = np.einsum("ktj,ktj->kt", tvec, pvec) * inv
        qvec = np.cross(tvec, e1)
        v = np.einsum("ktj,ktj->kt", d, qvec) * inv
        t = np.einsum("ktj,tj->kt", qvec, e2) * inv
        inside = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6) & (t < 1 - 1e-6) & (np.abs(det) > 1e-300)
        hit[i:i + chunk] = inside.any(axis=1)
    return hit


def camera_frame(lookat):
    """The camera of a Mitsuba <lookat origin=".." target=".." up=".."/> element's text: its origin,
    and its forward, right and up unit vectors (3,) each, in world space. ValueError when an
    attribute is missing, or when up is parallel to the view direction (no frame)."""
    vals = {k: np.array([float(x) for x in v.split(",")]) for k, v in re.findall(r'(origin|target|up)="([^"]*)"', lookat)}
    if set(vals) != {"origin", "target", "up"}:
        raise ValueError("lookat %r: expected origin, target and up" % lookat)
    f = vals["target"] - vals["origin"]
    f /= np.linalg.norm(f)
    r = np.cross(f, vals["up"])
    if not np.linalg.norm(r) > 1e-12 * np.linalg.norm(vals["up"]):
        raise ValueError("lookat %r: up is parallel to the view direction" % lookat)
    r /= np.linalg.norm(r)
    return vals["origin"], f, r, np.cross(r, f)


def in_view(q, camera, half_fov):
    """(k,) bool: whether the points q (k, 3) lie in the view of camera (camera_frame's tuple; a
    square film with half field of view half_fov in radians)."""
    o, f, r, u = camera
    d = q - o
    z = d @ f
    t = np.tan(half_fov)
    return (z > 0) & (np.abs(d @ r) <= z * t) & (np.abs(d @ u) <= z * t)


def seen_by_camera(points, V, F, scene, camera, half_fov):
    """Which points on the mesh V, F (n, 3) the camera (camera_frame's tuple; square film, half
    field of view half_fov in radians) sees: ((n,) bool directly, (n,) bool by one reflection in
    scene's mirror-left or mirror-right). Directly: in view, and the segment to the camera crosses
    no triangle. In a mirror: the segment from the point to the camera reflected in the mirror's
    plane meets the mirror's rectangle at a point m in view, and neither the way from the point to m
    nor the way from m to the camera crosses a triangle of V, F. The mirrors count as two-sided and
    block no way: both hold in scenes/two-mirrors.xml, where the bunny stands in front of them."""
    o = camera[0]
    direct = in_view(points, camera, half_fov)
    idx = np.nonzero(direct)[0]
    direct[idx[occluded(points[idx], np.broadcast_to(o, (len(idx), 3)), V, F)]] = False
    mirrored = np.zeros(len(points), dtype=bool)
    for mirror in ("mirror-left", "mirror-right"):
        M = scene.vertices(mirror)  # the rectangle's 4 corners
        c = M.mean(axis=0)
        n = np.cross(M[1] - M[0], M[2] - M[0])
        n /= np.linalg.norm(n)
        image = o - 2 * np.dot(o - c, n) * n  # the camera reflected across the mirror's plane
        d = image - points
        with np.errstate(divide="ignore", invalid="ignore"):  # a segment parallel to the plane: s not finite
            s = np.dot(c - points, n) / np.dot(d, n)  # where the segment meets the plane
            m = points + s[:, None] * d
        # Inside the rectangle: coordinates along its edges from the first corner (a rectangle's
        # corners come in order around it).
        ex, ey = M[1] - M[0], M[3] - M[0]
        lx = np.dot(m - M[0], ex) / np.dot(ex, ex)
        ly = np.dot(m - M[0], ey) / np.dot(ey, ey)
        on_mirror = (s > 0) & (s < 1) & (lx >= 0) & (lx <= 1) & (ly >= 0) & (ly <= 1)
        candidate = on_mirror & in_view(m, camera, half_fov) & ~mirrored
        idx = np.nonzero(candidate)[0]
        ok = ~occluded(points[idx], m[idx], V, F)
        idx = idx[ok]
        idx = idx[~occluded(m[idx], np.broadcast_to(o, (len(idx), 3)), V, F)]
        mirrored[idx] = True
    return direct, mirrored


def per_phase(text, phases):
    """One positive integer per phase from a comma list such as "64,128,256" (the last repeats):
    a list of `phases` ints. Raises ValueError for a non-integer, a value < 1 or more values than
    phases."""
    try:
        values = [int(v) for v in text.split(",")]
    except ValueError:
        raise ValueError("%r: expected a comma list of integers" % text) from None
    if min(values) < 1:
        raise ValueError("%r: values must be >= 1" % text)
    if len(values) > phases:
        raise ValueError("%r: %d values for %d phases" % (text, len(values), phases))
    return [values[min(i, len(values) - 1)] for i in range(phases)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build directory with python/qsil*.so")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "two-mirrors"))
    ap.add_argument("--seconds", type=float, default=1200, help="optimisation wall time per method")
    ap.add_argument("--res", default="64,64,128,128",
                    help="film size per phase (coarse to fine): a comma list, one per phase between remeshings "
                         "(the last repeats); the scoring and the pictures use the largest")
    ap.add_argument("--spp", default="4",
                    help="samples per pixel of each primal render and reverse run, per phase: a comma list as "
                         "--res (the last repeats)")
    ap.add_argument("--target-spp", type=int, default=1024)
    ap.add_argument("--subdiv", type=int, default=3, help="icosphere subdivisions of the start (3: 642 vertices)")
    ap.add_argument("--radius", type=float, default=0.6, help="radius of the start sphere (scene units)")
    ap.add_argument("--lr", type=float, default=0.04, help="Large Steps' step on u")
    ap.add_argument("--lam", type=float, default=19.0, help="lambda of (I + lambda L)")
    ap.add_argument("--remeshes", type=int, default=3, help="remeshings, at equal shares of the time")
    ap.add_argument("--lr-decay", type=float, default=0.7, help="step size factor at each remeshing")
    ap.add_argument("--min-edge", type=float, default=0.035, help="shortest target edge length of a remeshing")
    ap.add_argument("--methods", default="quadric,vsphere,none,quadric:2",
                    help="boundary methods to compare; METHOD:2 also fits the second camera's image (two targets)")
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

    phases = args.remeshes + 1
    try:
        res_of_phase = per_phase(args.res, phases)
        spp_of_phase = per_phase(args.spp, phases)
    except ValueError as e:
        ap.error("--res %r / --spp %r (--remeshes %d): %s" % (args.res, args.spp, args.remeshes, e))
    score_res = max(res_of_phase)
    os.makedirs(args.out, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="qsil-two-mirrors-")
    defines = {"res": str(score_res), "max_depth": "3"}

    # ---- The truth and the target images, one per film size of the schedule (fixed seeds).
    truth_scene = qsil.Scene(SCENE, defines)
    TV, TF = truth_scene.vertices("bunny"), truth_scene.triangles("bunny").astype(np.int64)
    distances = SurfaceDistance(TV, TF)
    second_xml = second_view_scene(tmp)
    second = qsil.Scene(second_xml, defines)
    targets_at = {}  # film size -> (camera's target, second camera's target)
    for r in sorted(set(res_of_phase)):
        truth_scene.set_resolution(r, r)
        second.set_resolution(r, r)
        targets_at[r] = (qsil.render(truth_scene, spp=args.target_spp, seed=1, threads=args.threads),
                         qsil.render(second, spp=args.target_spp, seed=2, threads=args.threads))
    truth_scene.set_resolution(score_res, score_res)
    second.set_resolution(score_res, score_res)
    target = targets_at[score_res][0]

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
    # The part of the truth the camera sees, directly or in a mirror (the scene's camera, on its
    # square film); the rest only the shape prior constrains.
    with open(SCENE) as f:
        xml = f.read()
    camera = camera_frame(camera_lookat(xml, SCENE))
    seen_direct, seen_mirrored = seen_by_camera(distances.points, TV, TF, truth_scene, camera,
                                                camera_half_fov(xml, SCENE))
    seen = seen_direct | seen_mirrored

    def score_shape(V, F):
        """Chamfer and Hausdorff distances, of the whole surface and of the part the camera sees."""
        return distances(V, F) + distances(V, F, part=seen)

    start_chamfer, start_hausdorff, start_seen_chamfer, start_seen_hausdorff = score_shape(V0, F0)
    spp_record = spp_of_phase if len(set(spp_of_phase)) > 1 else spp_of_phase[0]
    results = {"res": res_of_phase, "spp": spp_record, "target_spp": args.target_spp, "seconds": args.seconds,
               "lr": args.lr, "lam": args.lam, "remeshes": args.remeshes, "lr_decay": args.lr_decay,
               "start_vertices": int(len(V0)), "truth_vertices": int(len(TV)), "diag": distances.diag, "floor": floor,
               "min_edge": args.min_edge, "score_res": score_res, "threads": args.threads or os.cpu_count(),
               "seen_share": float(seen.mean()), "mirror_only_share": float((seen_mirrored & ~seen_direct).mean()),
               "start": {"chamfer": start_chamfer, "hausdorff": start_hausdorff, "seen_chamfer": start_seen_chamfer,
                         "seen_hausdorff": start_seen_hausdorff}, "methods": {}}
    evolution = {}
    for name in args.methods.split(","):
        method, _, views = name.partition(":")
        # The camera's scene, and with METHOD:2 the second camera's: one target and estimator each.
        scenes = [qsil.Scene(SCENE, defines)] + ([qsil.Scene(second_xml, defines)] if views == "2" else [])

        def start_phase(phase, V, F):
            """The phase's film size and mesh in every scene; its targets and new estimators."""
            r = res_of_phase[phase]
            for sc in scenes:
                sc.set_resolution(r, r)
                sc.set_mesh("bunny", V, F)
            return (list(targets_at[r][:len(scenes)]),
                    [qsil.ReverseEstimator(sc, ["bunny"], boundary=method) for sc in scenes])

        V, F = V0.copy(), F0.copy()
        phase = 0
        targets, estimators = start_phase(phase, V, F)
        opt = LargeSteps(V, F, lam=args.lam, lr=args.lr)

        def score(V, F):
            """The loss of the mesh V, F at the largest film size, rendered at a fixed seed (64 spp)."""
            truth_scene.set_mesh("bunny", V, F)
            img = qsil.render(truth_scene, spp=64, seed=5, threads=args.threads)
            return float(((img - target) ** 2).mean())

        loss0 = score(V, F)
        results["start"]["loss"] = loss0
        curve = [(0.0, 0, loss0, start_chamfer, start_hausdorff, int(len(V)), start_seen_chamfer,
                  start_seen_hausdorff)]
        snapshots = [(0.0, pictures(V, F))]
        elapsed, step, seed, refits, setups = 0.0, 0, 100, 0, len(scenes)
        progress = Progress(name, args.seconds)
        next_eval, next_remesh, next_picture = 0.1 * args.seconds, args.seconds / (args.remeshes + 1), 0.25
        while elapsed < args.seconds:
            t0 = time.perf_counter()
            grad = np.zeros_like(V)
            step_loss = 0.0
            for sc, est, tgt in zip(scenes, estimators, targets):
                image = est.render(spp=spp_of_phase[phase], seed=seed, threads=args.threads)
                step_loss += float(((image - tgt) ** 2).mean()) / len(scenes)
                w = 2 * (image - tgt) / (image.size * len(scenes))
                grad += est.run(w, spp=spp_of_phase[phase], seed=seed + 1, threads=args.threads)["gradient"]["bunny"]
                seed += 2
            V = opt.step(grad)
            step += 1
            if elapsed >= next_remesh and next_remesh < args.seconds:
                length = max(0.5 * mean_edge(V, F), args.min_edge)
                V, F = qsil.remesh(V, F, length)
                F = F.astype(np.int64)
                opt = opt.remeshed(V, F, lr_scale=args.lr_decay)
                phase += 1
                targets, estimators = start_phase(phase, V, F)
                setups += len(scenes)
                next_remesh += args.seconds / (args.remeshes + 1)
            else:
                for sc in scenes:
                    sc.set_vertices("bunny", V)
                for est in estimators:
                    u = est.update()
                    refits += bool(u["refitted"])
                    setups += not u["refitted"] and u["reason"] != "no boundary term"
            elapsed += time.perf_counter() - t0
            progress.show(elapsed, step, step_loss, "%d^2" % res_of_phase[phase])
            if elapsed >= next_eval or elapsed >= args.seconds:
                loss = score(V, F)
                chamfer, hausdorff, seen_chamfer, seen_hausdorff = score_shape(V, F)
                curve.append((elapsed, step, loss, chamfer, hausdorff, int(len(V)), seen_chamfer, seen_hausdorff))
                progress.clear()
                print("%-8s %7.1f s  step %5d (%.2f/s)  loss %.5f (floor %.5f)  chamfer %.2f %%  hausdorff %.2f %%  "
                      "seen part %.2f %% / %.2f %%  %d vertices"
                      % (name, elapsed, step, step / elapsed, loss, floor, 100 * chamfer, 100 * hausdorff,
                         100 * seen_chamfer, 100 * seen_hausdorff, len(V)), flush=True)
                next_eval += 0.1 * args.seconds
            if elapsed >= next_picture * args.seconds or elapsed >= args.seconds:
                snapshots.append((elapsed, pictures(V, F)))
                next_picture += 0.25
        progress.clear()
        t, s, loss, chamfer, hausdorff, nv, seen_chamfer, seen_hausdorff = curve[-1]
        results["methods"][name] = {"steps": step, "loss": loss, "chamfer": chamfer, "hausdorff": hausdorff,
                                      "vertices": nv, "refits": refits, "setups": setups, "curve": curve,
                                      "seen_chamfer": seen_chamfer, "seen_hausdorff": seen_hausdorff}
        evolution[name] = snapshots
        write_obj(os.path.join(args.out, "result-%s.obj" % name.replace(":", "-")), V, F)

    # ---- Charts: the loss and its floor, Chamfer and Hausdorff against time.
    progress_chart(os.path.join(args.out, "progress.png"), results["methods"], floor,
                   "Two mirrors: film %s per phase, %s spp per step, %d remeshings"
                   % (" -> ".join("%d^2" % r for r in res_of_phase),
                      " -> ".join(str(n) for n in spp_of_phase) if len(set(spp_of_phase)) > 1
                      else str(spp_of_phase[0]), args.remeshes),
                   seen=True, targets=(0.01, 0.05))
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
    write_record(args, results, RECORD, SCRIPT, page_text)


if __name__ == "__main__":
    main()
