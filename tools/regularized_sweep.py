#!/usr/bin/env python3
"""Bias, noise and cost of `qsil grad --boundary regularized` against the width of its blur
(docs/experiments/2026-11-26-regularized.md; issue 56 item 3).

Per scene: the quadric method at 4x the samples is the reference of the hard image's derivative;
then quadric and regularized at each width run at the same samples. For each: the derivative's
image sum and standard error, its bias z against the reference (sum - reference over the combined
standard error), the run's seconds, and SE^2 x seconds relative to quadric's (the inverse of the
efficiency ratio: 100 means quadric reaches the same noise in 1/100 of the time).

Usage: /usr/bin/python3 tools/regularized_sweep.py [--qsil build/qsil] [--root .] [--res 32] [--threads 2]
Prints a Markdown table (standard library only; the runs' EXRs go to a temporary folder).
"""
import argparse
import os
import re
import subprocess
import tempfile

CASES = [
    ("penumbra-sign", "tests/data/gradient/penumbra-sign.xml", "occluder:translate:0,1,0", 1024,
     ["1e-2", "3e-3", "1e-3", "3e-4", "1e-4"]),
    ("smooth-cube", "tests/data/gradient/smooth-cube.xml", "cube:translate:0,0,1", 1024,
     ["1e-2", "3e-3", "1e-3", "3e-4", "1e-4"]),
    ("shadow-quad", "scenes/shadow-quad.xml", "object:translate:1,0,0", 256, ["3e-3", "1e-3", "3e-4", "1e-4"]),
    ("spot-mirror", "scenes/spot-mirror.xml", "spot:translate:0,1,0", 256, ["3e-3", "1e-3", "3e-4", "1e-4"]),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--qsil", default="build/qsil")
    ap.add_argument("--root", default=".")
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    out_dir = tempfile.mkdtemp()

    def grad(scene, param, spp, *extra):
        out = subprocess.run([a.qsil, "grad", os.path.join(a.root, scene), "--param", param, "-D", f"res={a.res}",
                              "--spp", str(spp), "--seed", "7", "--threads", str(a.threads), "-o",
                              os.path.join(out_dir, "g.exr"), *extra], capture_output=True, text=True, check=True).stdout
        s = re.search(r"image sum (\S+) \+- (\S+)", out)
        t = re.search(r", ([0-9.]+) s \(set-up", out)
        return float(s.group(1)), float(s.group(2)), float(t.group(1))

    print("| scene | method | spp | image sum ± SE | bias z | seconds | SE² × s ÷ quadric's |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
    for name, scene, param, spp, widths in CASES:
        ref = grad(scene, param, 4 * spp)
        print(f"| {name} | quadric (reference) | {4 * spp} | {ref[0]:.4g} ± {ref[1]:.2g} | | {ref[2]:.2f} | |",
              flush=True)
        rows = [("quadric", grad(scene, param, spp))]
        rows += [(f"regularized {w}", grad(scene, param, spp, "--boundary", "regularized", "--reg-width", w))
                 for w in widths]
        base = rows[0][1][1] ** 2 * rows[0][1][2]
        for label, (s, se, sec) in rows:
            z = (s - ref[0]) / (se ** 2 + ref[1] ** 2) ** 0.5
            print(f"| {name} | {label} | {spp} | {s:.4g} ± {se:.2g} | {z:.1f} | {sec:.2f} | {se ** 2 * sec / base:.3g} |",
                  flush=True)


if __name__ == "__main__":
    main()
