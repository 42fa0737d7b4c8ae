#!/usr/bin/env python3
"""Cost of a gradient against the primal image on every bundled scene (a benchmark, not a test).

Usage: python3 tools/bench/grad_cost.py [--qsil build/qsil] [--res 256] [--spp 16] [--threads 2]
       [--perf] [--flat] [--record docs/images/cost/grad_cost.json]

For each scenes/*.xml with its chart parameter: `qsil render` and `qsil grad` (quadric) at the same
resolution and spp, run back to back (render, grad, render, grad: the machine's noise hits both),
and prints a table: render and grad wall time (the faster of two), grad / render, grad's split into
interior and boundary time, its traversals and their zero-contribution share. With --perf (Debian's
linux-perf), `perf record` of one more grad run gives the share of its samples inside Embree
(libembree3) and the five hottest qsil functions, and of one more render run the share of the primal
renderer's samples inside Embree (about what path shading reaches, in `grad` too). With
--flat, a second table: `grad` of each scene
and of the stability teapot and wingnut with every obj shape smooth-shaded (as bundled) and
flat-shaded (`face_normals`: every non-flat edge a crease, an always-candidate of the
always-candidate trees, docs/architecture.md §3), run back to back, and flat / smooth (issue 16's
target: at most 2). With --record FILE, the tables as data (JSON, written whole or not at all, with
the settings, CPU, date and the commit of the qsil measured): docs/images/cost/grad_cost.json is
the record tools/results_report.py judges issue 16's cost targets from.
"""
import json
import os
import re
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from references import argument_parser, cpu_model, git_commit  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENES = [("spot-mirror", "spot:translate:0,1,0"), ("shadow-quad", "object:translate:0,1,0"),
          ("direct", "spot:translate:1,0,0")]
FLAT_SCENES = [(os.path.join("scenes", s + ".xml"), p) for s, p in SCENES] + [
    (os.path.join("scenes", "stability", "teapot.xml"), "teapot:translate:0,1,0"),
    (os.path.join("scenes", "stability", "wingnut.xml"), "wingnut:translate:1,0,0")]


def run(cmd):
    """Runs a command in the repository root; returns its stdout (raises on failure)."""
    return subprocess.run(cmd, cwd=ROOT, check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True).stdout


def render_seconds(qsil, xml, common):
    """Wall time of `qsil render` from its summary line."""
    out = run([qsil, "render", xml, *common, "-o", os.path.join("out", "bench-render.exr")])
    return float(re.search(r"spp, ([0-9.]+) s", out).group(1))


def grad_stats(qsil, xml, param, common):
    """(wall, interior, boundary seconds, traversals, zero share %) of `qsil grad`."""
    out = run([qsil, "grad", xml, *common, "--param", param, "-o", os.path.join("out", "bench-grad.exr")])
    m = re.search(r"([0-9.]+) s \(set-up ([0-9.]+) s, interior ([0-9.]+) s, boundary ([0-9.]+) s\).*?"
                  r"(\d+) traversals, ([0-9.]+)% zero", out)
    return float(m.group(1)), float(m.group(3)), float(m.group(4)), int(m.group(5)), float(m.group(6))


def flat_copy(xml, folder):
    """Writes a copy of scene file `xml` (repository-relative) into `folder` with every obj shape
    flat-shaded (a face_normals boolean added) and every filename made absolute; returns its path.
    Raises SystemExit when the scene has no obj shape."""
    src = os.path.join(ROOT, xml)
    text = open(src).read()
    base = os.path.dirname(src)
    text = re.sub(r'(name="filename"\s+value=")([^"]+)"',
                  lambda m: m.group(1) + os.path.join(base, m.group(2)) + '"', text)
    text, n = re.subn(r'(<shape\s+type="obj"[^>]*>)', r'\1<boolean name="face_normals" value="true"/>', text)
    if n == 0:
        raise SystemExit(f"grad_cost: {xml} has no obj shape to flat-shade")
    out = os.path.join(folder, os.path.basename(xml))
    with open(out, "w") as f:
        f.write(text)
    return out


def flat_table(qsil, common):
    """Prints grad wall time smooth vs flat-shaded (the faster of two, run alternately); returns the rows."""
    print("\n| scene | grad s smooth | grad s flat | flat / smooth | traversals smooth / flat | zero % smooth / flat |")
    print("|---|---|---|---|---|---|")
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for xml, param in FLAT_SCENES:
            flat = flat_copy(xml, folder)
            sm, fl = [], []
            for _ in range(2):
                sm.append(grad_stats(qsil, xml, param, common))
                fl.append(grad_stats(qsil, flat, param, common))
            a, b = min(sm), min(fl)
            name = os.path.splitext(os.path.basename(xml))[0]
            ratio = b[0] / a[0] if a[0] > 0 else None
            print(f"| {name} | {a[0]:.2f} | {b[0]:.2f} | {'–' if ratio is None else f'{ratio:.2f}'} | "
                  f"{a[3]} / {b[3]} | {a[4]:.1f} / {b[4]:.1f} |", flush=True)
            rows.append({"scene": name, "param": param, "smooth_s": a[0], "flat_s": b[0], "flat_over_smooth": ratio,
                         "traversals_smooth": a[3], "traversals_flat": b[3], "zero_pct_smooth": a[4],
                         "zero_pct_flat": b[4]})
    return rows


def embree_share(qsil, xml, param, common):
    """(% of perf samples in libembree3, top five symbols) of one grad run, or of one render run when
    `param` is None."""
    data = os.path.join(ROOT, "out", "bench-perf.data")
    what = (["grad", xml, *common, "--param", param, "-o", os.path.join("out", "bench-grad.exr")] if param else
            ["render", xml, *common, "-o", os.path.join("out", "bench-render.exr")])
    subprocess.run(["perf", "record", "-q", "-F", "499", "-o", data, qsil, *what], cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    dso = run(["perf", "report", "-i", data, "--no-children", "--sort", "dso", "--stdio"])
    share = sum(float(m.group(1)) for m in re.finditer(r"([0-9.]+)%\s+libembree", dso))
    sym = run(["perf", "report", "-i", data, "--no-children", "--sort", "symbol", "--stdio"])
    top = [f"{m.group(2).strip()[:48]} {m.group(1)}%" for m in re.finditer(r"^\s+([0-9.]+)%\s+\[\.\]\s+(.*)$", sym,
                                                                            re.M)][:5]
    return share, top


def main():
    """Prints the table."""
    ap = argument_parser(__doc__, res=256)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--perf", action="store_true", help="also the share of grad's time inside Embree (perf)")
    ap.add_argument("--flat", action="store_true", help="also grad of each mesh flat-shaded against smooth-shaded")
    ap.add_argument("--record", default="", help="also write the tables as data (JSON) to this file")
    args = ap.parse_args()
    qsil = os.path.abspath(args.qsil)
    os.makedirs(os.path.join(ROOT, "out"), exist_ok=True)
    common = ["-D", f"res={args.res}", "--spp", str(args.spp), "--threads", str(args.threads), "-q"]
    record = {"commit": git_commit(), "date": time.strftime("%Y-%m-%d"), "cpu": cpu_model(), "res": args.res,
              "spp": args.spp, "threads": args.threads, "rows": []}
    print(f"grad_cost: {args.res}², {args.spp} spp, {args.threads} threads, quadric boundary term")
    print("| scene | render s | grad s | grad / render | interior s | boundary s | traversals | zero % |"
          + (" Embree % of grad | Embree % of render | hottest |" if args.perf else ""))
    print("|---|---|---|---|---|---|---|---|" + ("---|---|---|" if args.perf else ""))
    for scene, param in SCENES:
        xml = os.path.join("scenes", scene + ".xml")
        r, g = [], []
        for _ in range(2):
            r.append(render_seconds(qsil, xml, common))
            g.append(grad_stats(qsil, xml, param, common))
        rs, gs = min(r), min(g)
        ratio = gs[0] / rs if rs > 0 else None  # a render under the summary's 10 ms resolution has none
        row = (f"| {scene} | {rs:.2f} | {gs[0]:.2f} | {'–' if ratio is None else f'{ratio:.1f}'} | {gs[1]:.2f} | "
               f"{gs[2]:.2f} | {gs[3]} | {gs[4]:.1f} |")
        rec = {"scene": scene, "param": param, "render_s": rs, "grad_s": gs[0], "grad_over_render": ratio,
               "interior_s": gs[1], "boundary_s": gs[2], "traversals": gs[3], "zero_pct": gs[4]}
        if args.perf:
            share, top = embree_share(qsil, xml, param, common)
            render_share, _ = embree_share(qsil, xml, None, common)
            row += f" {share:.1f} | {render_share:.1f} | {'; '.join(top)} |"
            rec.update({"embree_pct": share, "render_embree_pct": render_share, "hottest": top})
        record["rows"].append(rec)
        print(row, flush=True)
    if args.flat:
        record["flat"] = flat_table(qsil, common)
    if args.record:
        path = os.path.abspath(args.record)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path + ".tmp", "w") as f:
            json.dump(record, f, indent=1)
        os.replace(path + ".tmp", path)
        print(f"grad_cost: recorded in {args.record}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
