#!/usr/bin/env python3
"""Instructions of the edge choice, part by part, for one or two builds (a benchmark, not a test).

Usage: python3 tools/bench/edge_choice_instructions.py --qsil build/qsil [--base OTHER/qsil]
       [--res 32] [--spp 16] [--scenes spot-mirror,shadow-quad,direct,stability/teapot]

Runs `qsil grad` (quadric boundary term, one thread, a fixed seed) under Debian's valgrind
(`callgrind`, which counts executed instructions) and prints, per scene, the instructions (millions)
of the render loop and, inside it, of the edge choice (sample_silhouette_set) and its parts: the
top level (roots and loose edges: their tests and node weights), the descent's child choices
(rejection tests and node weights), its flat choices (the scan and the leaf-edge weights), the
point on the chosen edge (sample_on_edge) and the node and leaf-edge weights wherever they are
called. With --base, the same for a second build, and the ratio new / base per part.

Why instructions: on a small shared machine (2 cores, run-to-run noise of 10-20 % in wall time)
a 5 % change of the edge choice's cost cannot be seen in wall time without dozens of runs, while
instruction counts of one run repeat exactly (the same seed takes the same choices). They are not
time: a division and an addition count alike, and cache misses not at all, so a change judged by
instructions is confirmed by `tools/bench/grad_cost.py` (wall time) before it is called a speed-up.
Callgrind runs about 50x slower than the program: 32², 16 spp takes a minute per scene and build.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PARAMS = {"spot-mirror": "spot:translate:0,1,0", "shadow-quad": "object:translate:0,1,0",
          "direct": "spot:translate:1,0,0", "stability/teapot": "teapot:translate:0,1,0",
          "stability/wingnut": "wingnut:translate:1,0,0"}
# (column, pattern of the function's name in callgrind_annotate's inclusive listing)
PARTS = [("render loop", r"GradientEstimator<1>::run\(qsil::RenderOptions const&, int, int, qsil::RenderResult&\) "
                         r"const::\{lambda"),
         ("edge choice", r"edgetree::sample_silhouette_set\("),
         ("top level", r"::top_level\("),
         ("child choices", r"::child_candidates\("),
         ("flat choices", r"::flat_candidates\("),
         ("point on edge", r"::sample_on_edge\(qsil::edgetree::Edge const&, double, qsil::edgetree::\(anonymous"),
         ("node weights", r"::node_weight\(qsil::edgetree::ForestNode const&, qsil::edgetree::\(anonymous"),
         ("leaf-edge weights", r"::leaf_edge_weight\(qsil::edgetree::Edge const&, qsil::edgetree::\(anonymous")]


def instructions(qsil, scene, res, spp):
    """{part: instructions} of one grad run of `scene` under callgrind."""
    xml = os.path.join(ROOT, "scenes", scene + ".xml")
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "callgrind.out")
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", qsil, "grad", xml, "--param",
               PARAMS[scene], "-D", f"res={res}", "--spp", str(spp), "--seed", "1", "--threads", "1", "-q",
               "-o", os.path.join(folder, "grad.exr")]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        listing = subprocess.run(["callgrind_annotate", "--inclusive=yes", out], check=True,
                                 stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True).stdout
    counts = {}
    for name, pattern in PARTS:
        m = re.search(r"^\s*([0-9,]+) \([ 0-9.]+%\)\s+[^\n]*?" + pattern, listing, re.M)
        counts[name] = int(m.group(1).replace(",", "")) if m else 0
    return counts


def main():
    """Prints the table."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--qsil", default=os.path.join(ROOT, "build", "qsil"), help="the build measured")
    ap.add_argument("--base", default="", help="a second build to compare with (ratio new / base)")
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--scenes", default="spot-mirror,shadow-quad,direct,stability/teapot")
    args = ap.parse_args()
    if not shutil.which("valgrind") or not shutil.which("callgrind_annotate"):
        sys.exit("edge_choice_instructions: valgrind is not installed (Debian: apt-get install valgrind)")
    scenes = [s for s in args.scenes.split(",") if s]
    for s in scenes:
        if s not in PARAMS:
            sys.exit(f"edge_choice_instructions: no parameter known for scene '{s}' (known: {', '.join(PARAMS)})")
    builds = [("new", os.path.abspath(args.qsil))] + ([("base", os.path.abspath(args.base))] if args.base else [])
    for _, path in builds:
        if not os.access(path, os.X_OK):
            sys.exit(f"edge_choice_instructions: {path} is not an executable qsil")
    print(f"edge_choice_instructions: {args.res}², {args.spp} spp, 1 thread, seed 1; millions of instructions")
    head = "| scene | build | " + " | ".join(name for name, _ in PARTS) + " |"
    print(head)
    print("|---|---|" + "---|" * len(PARTS))
    for scene in scenes:
        rows = {label: instructions(path, scene, args.res, args.spp) for label, path in builds}
        for label, counts in rows.items():
            print(f"| {scene} | {label} | " + " | ".join(f"{counts[n] / 1e6:.1f}" for n, _ in PARTS) + " |",
                  flush=True)
        if args.base:
            new, base = rows["new"], rows["base"]
            print(f"| {scene} | new / base | " + " | ".join(
                f"{new[n] / base[n]:.3f}" if base[n] else "–" for n, _ in PARTS) + " |", flush=True)


if __name__ == "__main__":
    main()
