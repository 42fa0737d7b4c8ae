#!/usr/bin/env python3
"""Where a gradient's tail comes from: runs `qsil grad --largest-samples K` over several seeds and
splits the sum of squares of the kept samples by term, path depth, cosine at the hit and surface.

The largest samples of a heavy-tailed estimator hold most of its variance. So the split of their
sum of squares says which cause to attack first:
- the interior term against the secondary boundary term;
- for the interior part, the vertex where most of each sample's derivative arises (`arises` of
  `qsil grad --largest-samples-csv`: what the vertex's own shading and hit add, and the derivative
  of the throughput factor it passes on times all that later vertices collect; not `added`, which
  files a derivative under the vertex that collects the light, e.g. a mirror that brings a bright
  sky to a diffuse hit whose normal turns fast; the first vertex's includes an attached camera
  ray's Jacobian term, whose share is reported too): its depth (segments before it), its
  |n_g . wo| in decades (grazing hits slide fast along their rays), the rate at which its
  shading normal turns along the slide, |dn_s/dtheta| / |dp/dtheta| in decades (per scene unit:
  large on small triangles whose vertex normals differ much, e.g. smoothed creases), and the
  surface it lies on;
- for the boundary part, the edge point that adds the most to each sample (the retrace evaluates
  the boundary term again and records it): its vertex's depth, what the edge is (silhouette,
  crease, smoothed crease, intersection curve), its shape and whether that is the shape the vertex
  lies on (an edge of the vertex's own rigidly moving shape moves relative to it only by the hit's
  slide along its ray), and in decades its pdf, its distance from the vertex and |sin| of the
  angle at which the edge is seen. The retrace's boundary sum must equal value - interior; the
  report prints the largest relative mismatch (the CSV's 9 digits set a floor near 5e-9).

Usage: /usr/bin/python3 tools/tail_report.py SCENE --param P [--qsil build/qsil] [--spp 64] [--res 48]
       [--seeds 8] [--first-seed 100] [--keep 32] [--boundary quadric] [--threads 2] [-D name=value ...]
Prints one table; the CSVs stay in a temporary folder that is removed at exit.
"""
import argparse
import collections
import csv
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def cosine_bucket(c):
    """The decade of |n_g . wo| as a label."""
    for edge in (1e-4, 1e-3, 1e-2, 1e-1):
        if c < edge:
            return f"< {edge:g}"
    return ">= 0.1"


def turn_bucket(rate):
    """The decade of |dn_s/dtheta| / |dp/dtheta| (per scene unit) as a label."""
    for edge in (1.0, 10.0, 100.0):
        if rate < edge:
            return f"< {edge:g}"
    return ">= 100"


def decade(x, edges):
    """The decade of x among `edges` (ascending) as a label."""
    for edge in edges:
        if x < edge:
            return f"< {edge:g}"
    return f">= {edges[-1]:g}"


EDGE_KINDS = {"0": "silhouette", "1": "crease", "2": "smoothed crease", "3": "intersection curve"}
PDF_EDGES = (1e-3, 1e-2, 1e-1, 1.0, 10.0)
DISTANCE_EDGES = (1e-3, 1e-2, 1e-1, 1.0)
SIN_EDGES = (1e-3, 1e-2, 1e-1)


def order_of(edges):
    """The labels of decade() for `edges`, in ascending order."""
    return [f"< {e:g}" for e in edges] + [f">= {edges[-1]:g}"]


def run_seed(args, seed, path):
    """One `qsil grad` run writing its largest samples to `path`; exits with qsil's message on failure."""
    cmd = [args.qsil, "grad", args.scene, "--param", args.param, "--spp", str(args.spp), "-D", f"res={args.res}",
           "--seed", str(seed), "--threads", str(args.threads), "--boundary", args.boundary, "-q",
           "-o", os.path.join(os.path.dirname(path), "g.exr"), "--largest-samples", str(args.keep),
           "--largest-samples-csv", path]
    for d in args.define:
        cmd += ["-D", d]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"tail_report: {' '.join(cmd)}: {r.stderr.strip() or r.returncode}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--param", required=True)
    ap.add_argument("--qsil", default=os.path.join(ROOT, "build", "qsil"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", type=int, default=48)
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--first-seed", type=int, default=100)
    ap.add_argument("--keep", type=int, default=32, help="largest samples kept per seed")
    ap.add_argument("--boundary", default="quadric")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("-D", dest="define", action="append", default=[])
    args = ap.parse_args()
    by_term = collections.Counter()
    by_depth, by_cos, by_surface = collections.Counter(), collections.Counter(), collections.Counter()
    by_turn = collections.Counter()
    jacobian = 0.0  # the interior squares' part in attached camera rays' Jacobian terms
    b_depth, b_kind, b_shape = collections.Counter(), collections.Counter(), collections.Counter()
    b_pdf, b_distance, b_sin = collections.Counter(), collections.Counter(), collections.Counter()
    b_own = collections.Counter()
    mismatch = 0.0
    samples = 0
    largest = (0.0, None)
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            path = os.path.join(tmp, f"{seed}.csv")
            run_seed(args, seed, path)
            rows = collections.defaultdict(list)
            for row in csv.DictReader(open(path)):
                rows[row["rank"]].append(row)
            for vertices in rows.values():
                head = vertices[0]
                value, interior = float(head["value"]), float(head["interior"])
                samples += 1
                if abs(value) > abs(largest[0]):
                    largest = (value, (seed, head["x"], head["y"], head["sample"]))
                # The sample's square split between its two terms in proportion to their squares.
                total_sq = interior ** 2 + (value - interior) ** 2
                share = value ** 2 / total_sq if total_sq > 0 else 0.0
                by_term["interior"] += interior ** 2 * share
                by_term["boundary"] += (value - interior) ** 2 * share
                with_vertex = [v for v in vertices if v["segments"] != ""]
                if with_vertex and interior != 0:
                    top = max(with_vertex, key=lambda v: abs(float(v["arises"])))
                    w = interior ** 2 * share
                    parts = sum(abs(float(v["arises"])) for v in with_vertex)
                    if parts > 0:
                        jacobian += w * min(1.0, abs(float(head.get("camera_jacobian") or 0.0)) / parts)
                    by_depth[int(top["segments"])] += w
                    by_cos[cosine_bucket(float(top["cos_geometric"]))] += w
                    by_surface[top["shape"]] += w
                    dp, dns = float(top["dp"]), float(top["dns"])
                    by_turn[turn_bucket(dns / dp if dp > 0 else math.inf)] += w
                boundary = value - interior
                if head.get("b_total", "") != "":
                    scale = abs(value) + abs(interior)
                    if scale > 0:
                        mismatch = max(mismatch, abs(float(head["b_total"]) - boundary) / scale)
                if boundary != 0 and head.get("b_segments", "") != "":
                    w = boundary ** 2 * share
                    b_depth[int(head["b_segments"])] += w
                    b_kind[EDGE_KINDS.get(head["b_kind"], head["b_kind"])] += w
                    b_shape[head["b_shape"]] += w
                    at = [v for v in with_vertex if v["segments"] == head["b_segments"]]
                    own = "curve" if head["b_kind"] == "3" else "own" if at and at[0]["shape"] == head["b_shape"] else "other"
                    b_own[own] += w
                    b_pdf[decade(float(head["b_pdf"]), PDF_EDGES)] += w
                    b_distance[decade(float(head["b_distance"]), DISTANCE_EDGES)] += w
                    b_sin[decade(float(head["b_sin_view"]), SIN_EDGES)] += w
    total = sum(by_term.values())
    if total == 0:
        print("tail_report: no non-zero sample")
        return 0
    print(f"{args.scene} {args.param} {args.boundary}, {args.spp} spp, {args.res}^2, seeds "
          f"{args.first_seed}..{args.first_seed + args.seeds - 1}, the {args.keep} largest samples of each "
          f"({samples} in all); largest {largest[0]:.4g} at seed, x, y, sample = {largest[1]}")
    print("share of their sum of squares:")
    print("  term:      " + ", ".join(f"{k} {v / total:.2f}" for k, v in by_term.most_common()))
    interior = by_term["interior"] or math.inf
    print("  interior, by the vertex where most of it arises:")
    print("    depth:   " + ", ".join(f"{k} {v / interior:.2f}" for k, v in sorted(by_depth.items())))
    order = ["< 0.0001", "< 0.001", "< 0.01", "< 0.1", ">= 0.1"]
    print("    |ng.wo|: " + ", ".join(f"{k} {by_cos[k] / interior:.2f}" for k in order if k in by_cos))
    print("    |dns|/|dp|: " + ", ".join(f"{k} {by_turn[k] / interior:.2f}" for k in ["< 1", "< 10", "< 100", ">= 100"]
                                       if k in by_turn))
    print("    surface: " + ", ".join(f"{k} {v / interior:.2f}" for k, v in by_surface.most_common()))
    print(f"    of which the attached camera rays' Jacobian terms (at depth 1): {jacobian / interior:.2f}")
    boundary = by_term["boundary"] or math.inf
    print("  boundary, by the edge point that adds the most:")
    print("    depth:   " + ", ".join(f"{k} {v / boundary:.2f}" for k, v in sorted(b_depth.items())))
    print("    edge:    " + ", ".join(f"{k} {v / boundary:.2f}" for k, v in b_kind.most_common()))
    print("    shape:   " + ", ".join(f"{k} {v / boundary:.2f}" for k, v in b_shape.most_common()))
    print("    edge on the vertex's own shape: " + ", ".join(f"{k} {v / boundary:.2f}" for k, v in b_own.most_common()))
    for label, counter, edges in (("pdf", b_pdf, PDF_EDGES), ("distance", b_distance, DISTANCE_EDGES),
                                  ("|sin|", b_sin, SIN_EDGES)):
        print(f"    {label + ':':9}" + ", ".join(f"{k} {counter[k] / boundary:.2f}" for k in order_of(edges)
                                               if k in counter))
    print(f"  retrace check: largest |boundary sum - (value - interior)| / (|value| + |interior|) = {mismatch:.2g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
