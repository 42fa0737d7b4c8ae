#!/usr/bin/env python3
"""Set-up cost against triangle count (a benchmark, not a test; issue 54's scale targets).

Usage: python3 tools/bench/setup_scale.py [--qsil build/qsil] [--subdivisions 5,6,7,8]
       [--threads 2] [--repeat 2] [--keep DIR]

Meshes: perturbed icospheres, as the issue measured: `icosphere(s)` of
tests/data/meshes/icosphere.py (20 x 4^s triangles: 20 k, 82 k, 328 k, 1.31 M for s = 5..8) with
every vertex scaled by a random factor in [1, 1.01) (seed 1), smooth-shaded (qsil's area-weighted
vertex normals), about half of their edges concave creases. Each replaces Spot in
scenes/direct.xml (courtyard.exr, a backdrop). Per mesh, the best of --repeat runs of:
- `qsil render` at 8², 1 spp: wall time of the whole process (OBJ loading, Embree's BVH, the
  environment map: a render's set-up) and peak RSS;
- `qsil forest`: the edge forest with quadrics and intersection curves (its own timer), edges per
  second, the forest's bytes per edge (array capacities) and peak RSS; the intersection curves'
  own timer (they are found beside the shapes' trees, so their time overlaps the rest);
- `qsil grad` at 8², 1 spp, `spot:translate:0,1,0`: the boundary term's set-up time (forest and
  primary edges, its own timer) and peak RSS.
Prints a Markdown table and the issue's targets at 1.3 M triangles (load <= 1.5 s, forest <= 2 s,
>= 1 M edges/s, <= 150 bytes per edge). Peak RSS comes from os.wait4 (no /usr/bin/time needed).
"""
import argparse
import os
import random
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "data", "meshes"))
from icosphere import icosphere  # noqa: E402


def write_mesh(path, subdivisions, seed=1):
    """A perturbed icosphere (unit radius times [1, 1.01)) as OBJ; returns its triangle count."""
    verts, faces = icosphere(subdivisions)
    rng = random.Random(seed)
    with open(path, "w") as f:
        for v in verts:
            r = 1.0 + 0.01 * rng.random()
            f.write("v %.9f %.9f %.9f\n" % tuple(c * r for c in v))
        for a, b, c in faces:
            f.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))
    return len(faces)


def write_scene(path, mesh):
    """scenes/direct.xml with Spot replaced by `mesh` and the environment map's path absolute."""
    with open(os.path.join(ROOT, "scenes", "direct.xml")) as f:
        xml = f.read()
    if "meshes/spot.obj" not in xml or "envmaps/courtyard.exr" not in xml:
        sys.exit("setup_scale: scenes/direct.xml no longer names meshes/spot.obj and envmaps/courtyard.exr")
    xml = xml.replace("meshes/spot.obj", mesh)
    xml = xml.replace("envmaps/courtyard.exr", os.path.join(ROOT, "scenes", "envmaps", "courtyard.exr"))
    with open(path, "w") as f:
        f.write(xml)


def run(cmd):
    """Runs cmd; returns (stdout + stderr, wall seconds, peak RSS in MB). Exits on failure."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    out = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    seconds = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit("setup_scale: %s failed (%d):\n%s" % (" ".join(cmd), p.returncode, out))
    return out, seconds, usage.ru_maxrss / 1024.0


def measure(qsil, scene, threads, repeat):
    """The best of `repeat` runs of each command (times and RSS are each the smallest seen)."""
    common = ["--threads", str(threads)]
    best = {}

    def keep(key, value):
        best[key] = min(best.get(key, value), value)

    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            _, s, rss = run([qsil, "render", scene, "-D", "res=8", "--spp", "1", "-q", "-o",
                             os.path.join(tmp, "r.exr")] + common)
            keep("load_s", s)
            keep("render_rss", rss)
            out, _, rss = run([qsil, "forest", scene, "--stats"] + common)
            m = re.search(r"forest: \d+ shapes, (\d+) edges .*, ([0-9.]+) s, ([0-9.]+) bytes/edge", out)
            c = re.search(r"intersection curves: .*?([0-9.]+) s \(BVH", out)
            if not m:
                sys.exit("setup_scale: no forest line in:\n" + out)
            best["edges"] = int(m.group(1))
            keep("forest_s", float(m.group(2)))
            best["bytes_per_edge"] = float(m.group(3))
            keep("crossings_s", float(c.group(1)) if c else 0.0)
            keep("forest_rss", rss)
            out, _, rss = run([qsil, "grad", scene, "--param", "spot:translate:0,1,0", "-D", "res=8", "--spp", "1",
                               "-o", os.path.join(tmp, "g.exr")] + common)
            g = re.search(r"set-up ([0-9.]+) s", out)
            if not g:
                sys.exit("setup_scale: no set-up time in:\n" + out)
            keep("grad_setup_s", float(g.group(1)))
            keep("grad_rss", rss)
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--qsil", default=os.path.join(ROOT, "build", "qsil"))
    ap.add_argument("--subdivisions", default="5,6,7,8")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--keep", help="write the meshes and scenes here (default: a temporary folder)")
    a = ap.parse_args()
    if not os.access(a.qsil, os.X_OK):
        sys.exit("setup_scale: no qsil at %s (--qsil)" % a.qsil)
    subs = [int(s) for s in a.subdivisions.split(",")]
    work = a.keep or tempfile.mkdtemp(prefix="qsil-setup-scale-")
    os.makedirs(work, exist_ok=True)
    rows = []
    for s in subs:
        mesh = os.path.join(work, "icosphere%d.obj" % s)
        scene = os.path.join(work, "icosphere%d.xml" % s)
        triangles = write_mesh(mesh, s)
        write_scene(scene, mesh)
        r = measure(a.qsil, scene, a.threads, a.repeat)
        r["triangles"] = triangles
        rows.append(r)
        print("subdivisions %d: %d triangles done" % (s, triangles), file=sys.stderr)
    print("| triangles | edges | load (s) | forest (s) | crossings, overlapped (s) | M edges/s | bytes/edge | "
          "forest RSS (MB) | grad set-up (s) | grad RSS (MB) |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print("| %d | %d | %.2f | %.2f | %.2f | %.2f | %.0f | %.0f | %.2f | %.0f |" % (
            r["triangles"], r["edges"], r["load_s"], r["forest_s"], r["crossings_s"],
            r["edges"] / r["forest_s"] / 1e6, r["bytes_per_edge"], r["forest_rss"], r["grad_setup_s"], r["grad_rss"]))
    big = max(rows, key=lambda r: r["triangles"])
    print("\nIssue 54's targets at 1.3 M triangles (measured at %d): load <= 1.5 s: %.2f; forest <= 2 s: %.2f; "
          ">= 1 M edges/s: %.2f M; <= 150 bytes/edge: %.0f" % (
              big["triangles"], big["load_s"], big["forest_s"], big["edges"] / big["forest_s"] / 1e6,
              big["bytes_per_edge"]))
    if not a.keep:
        for s in subs:
            for ext in ("obj", "xml"):
                os.remove(os.path.join(work, "icosphere%d.%s" % (s, ext)))
        os.rmdir(work)


if __name__ == "__main__":
    main()
