#!/usr/bin/env python3
"""Stability study: every gradient method at equal (small) time on scenes/stability/*.xml, where
methods are known or expected to fail; writes docs/stability.md, the grids in
docs/images/stability/<name>/ and, for a whole study (not --only), the table as data in
docs/images/stability/results.json (write_record; tools/results_report.py reads it).

Usage: python3 tools/stability_study.py [--qsil PATH] [--budget 2] [--repeats 3] [--res 48]
       [--ref-spp 32768] [--ref-step-factor 0.25] [--threads 2] [--only NAME,...]
       [--force-references]

Per scene (scenes/stability/params.txt lists name, parameter, question): an FD reference
(`qsil reference --method fd`, per-pixel standard errors) at --ref-step-factor times qsil's
default step h0, so that FD in the table (at h0, what a user gets) is charged for the blur of its
step instead of sharing it with the reference (on `teapot` FD at h0 and at h0/4 differ pixel by
pixel by 0.059 x the mean square, docs/design-notes.md), then --repeats `qsil compare` processes
per method at --budget seconds each, with seeds 0 .. R-1, so that a crash of one method is
recorded and does not stop the others, and so that one lucky or unlucky run of a heavy-tailed
estimator does not decide a row (pool_runs: the mean relative MSE). Reported: non-finite pixels
(must be 0), agreement of the image sum with the reference (z = error / combined standard error;
|z| < 3 passes; FD is biased by O(h^2)), relative MSE, and the zero-contribution rate of the
boundary samples. qsil runs in the repository root with
repository-relative paths, so the results.json files carry no absolute paths.

References are cached (most of the study's time): out/stability/<name>-ref.exr is reused when its
record (<name>-ref.json) holds the same scene files (references.scene_digest: the XML and every mesh
and map it names), parameter, resolution, spp, steps and threads; --force-references re-renders
them. FD references use the primal renderer alone, so an estimator change leaves them valid; after
a change to the primal renderer, force them. The record keeps the commit that rendered it.
"""
import json
import os
import shutil
import subprocess
import sys
import time

from references import JUDGE_FLOOR_SHARE, argument_parser, default_steps, git_commit, scene_digest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
METHODS = ["quadric", "quadric-box", "vsphere", "uniform", "fd"]


def reference_key(args, xml, param, steps):
    """What a cached reference must have been made from (see the module docstring)."""
    return {"scene": scene_digest(xml), "param": param, "res": args.res, "spp": args.ref_spp,
            "steps": [f"{h:.9g}" for h in steps], "threads": args.threads}


def make_reference(args, xml, common, param, steps, ref):
    """Renders the FD reference `ref` (relative to ROOT), or reuses it when its record matches
    (reference_key) and --force-references is not given; writes the record after a render, so a
    failed or interrupted one leaves none. Returns None, or the error to record for every method."""
    key = reference_key(args, xml, param, steps)
    record = ref[:-len(".exr")] + ".json"
    if not args.force_references and os.path.exists(ref) and os.path.exists(record):
        made = json.load(open(record))
        if made.get("key") == key:
            print(f"{ref}: reused (rendered by {made.get('commit', 'unknown')})", flush=True)
            return None
    if os.path.exists(record):
        os.remove(record)
    commit = git_commit()
    r = subprocess.run([args.qsil, "reference", xml, *common, "--method", "fd", "--spp", str(args.ref_spp), "-q",
                        "-o", ref, *sum((["--h", f"{h:.9g}"] for h in steps), [])], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"{ref}: reference failed: {r.stderr.strip()[-300:]}", flush=True)
        return f"reference failed ({r.returncode})"
    with open(record, "w") as f:
        json.dump({"key": key, "commit": commit}, f)
    return None


def pool_runs(runs, ref_se):
    """One method's row from its `runs` (compare rows of independent seeds against one reference whose
    image-sum standard error is `ref_se`): rel_mse is their mean (the expected squared error, which a
    heavy-tailed estimator's single run misjudges both ways), rel_mse_runs each run's; z is the mean
    image-sum error over sqrt(mean se² / R + ref_se²) (the reference's error is common to the runs);
    spp and the zero-contribution rate are means, non-finite pixels a sum."""
    R = len(runs)
    row = {k: v for k, v in runs[0].items() if k not in ("sum_error", "sum_se")}
    row["rel_mse_runs"] = [r["rel_mse"] for r in runs]
    row["rel_mse"] = sum(row["rel_mse_runs"]) / R
    row["spp"] = round(sum(r["spp"] for r in runs) / R)
    row["wall_seconds"] = sum(r["wall_seconds"] for r in runs) / R
    row["nonfinite_pixels"] = sum(r["nonfinite_pixels"] for r in runs)
    zr = [r.get("zero_contribution_rate") for r in runs]
    row["zero_contribution_rate"] = None if None in zr else sum(zr) / R
    error = sum(r["sum_error"][0] for r in runs) / R
    se = (sum(r["sum_se"][0] ** 2 for r in runs) / R / R + ref_se ** 2) ** 0.5
    row["z"] = error / se if se > 0 else float("nan")
    return row


def run_methods(args, xml, common, ref, work, img_root, name):
    """args.repeats `qsil compare` processes per method against the reference, with seeds 0 .. R-1
    (the first one's images go to the grid); returns {method: pooled row (pool_runs) or error}."""
    per = {}
    for m in METHODS:
        runs, ref_se, error = [], 0.0, None
        for repeat in range(args.repeats):
            d = os.path.join(work, name, m if repeat == 0 else f"{m}-{repeat}")
            shutil.rmtree(d, ignore_errors=True)
            r = subprocess.run([args.qsil, "compare", xml, *common, "--methods", m, "--budgets", str(args.budget),
                                "--reference", ref, "--seed", str(repeat), "--no-plot", "-q", "--out", d],
                               capture_output=True, text=True)
            if r.returncode != 0:
                msg = r.stderr.strip().splitlines()[-1][:120] if r.stderr.strip() else ""
                error = (f"exit {r.returncode}" + (" (crash)" if r.returncode < 0 else "") + (f": {msg}" if msg else "")
                         + (f" (seed {repeat})" if repeat else ""))
                break
            res = json.load(open(os.path.join(d, "results.json")))
            runs.append(res["rows"][0])
            ref_se = res["reference"]["sum_se"][0]
            floor = res["reference"]["rel_noise_floor"]
        if error:
            per[m] = {"error": error}
        else:
            per[m] = pool_runs(runs, ref_se)
            per[m]["rel_noise_floor"] = floor
            os.makedirs(os.path.join(img_root, name), exist_ok=True)
        print(f"{name} {m}: {per[m].get('error', 'rel MSE %.3g' % per[m].get('rel_mse') if per[m].get('rel_mse') is not None else '?')}"
              + (" (runs " + ", ".join(f"{x:.3g}" for x in per[m]["rel_mse_runs"]) + ")" if "rel_mse_runs" in per[m] else ""),
              flush=True)
    return per


def merge_images(per, work, img_root, name, param):
    """The reference and each method's derivative in one grid (plot_compare.py on a merged run)."""
    merged = os.path.join(work, name, "merged")
    os.makedirs(os.path.join(merged, "images"), exist_ok=True)
    rows, methods, resj = [], [], None
    for m in METHODS:
        d = os.path.join(work, name, m)
        if "error" in per[m]:
            continue
        resj = json.load(open(os.path.join(d, "results.json")))
        rows += resj["rows"]
        methods.append(m)
        shutil.copy(os.path.join(d, "images", m + ".npy"), os.path.join(merged, "images", m + ".npy"))
        for f in ("reference.npy", "reference_se2.npy"):
            shutil.copy(os.path.join(d, "images", f), os.path.join(merged, "images", f))
    if resj:
        resj["rows"], resj["methods"] = rows, methods
        json.dump(resj, open(os.path.join(merged, "results.json"), "w"))
        subprocess.run([sys.executable, os.path.join("tools", "plot_compare.py"), merged, "--title",
                        f"stability/{name}: {param}"], check=True)
        os.makedirs(os.path.join(img_root, name), exist_ok=True)
        if os.path.exists(os.path.join(merged, "grid.png")):
            shutil.copy(os.path.join(merged, "grid.png"), os.path.join(img_root, name, "grid.png"))


def cell(row):
    """One table cell: non-finite pixels / relative MSE (the runs' range) / z / zero-contribution rate (spp)."""
    if "error" in row:
        return f"**{row['error']}**"
    zr = row.get("zero_contribution_rate")
    z = row.get("z")
    ok = "ok" if z is not None and abs(z) < 3 else "**differs**"
    runs = row.get("rel_mse_runs") or []
    spread = f" ({min(runs):.3g}–{max(runs):.3g})" if len(runs) > 1 else ""
    return (f"{row['nonfinite_pixels']} / {row['rel_mse']:.3g}{spread} / z={z:+.1f} {ok} / "
            + (f"{100 * zr:.0f}%" if zr is not None else "–") + f" ({row['spp']} spp)")


def floor_cell(per):
    """The reference's relative noise floor over the best relative MSE, flagged when above JUDGE_FLOOR_SHARE."""
    rows = [r for r in per.values() if "error" not in r and r.get("rel_mse")]
    if not rows or rows[0].get("rel_noise_floor") is None:
        return "–"
    ratio = rows[0]["rel_noise_floor"] / min(r["rel_mse"] for r in rows)
    return f"{ratio:.2f}" + ("" if ratio <= JUDGE_FLOOR_SHARE else " **high**")


def write_report(args, table, elapsed, img_root):
    """Writes docs/stability.md from the per-scene results."""
    lines = ["# Stability study", "",
             "Generated by `tools/stability_study.py` (do not edit by hand). Scenes: `scenes/stability/` "
             "(each file's comment states its question). Every method runs for the same wall-clock budget "
             f"({args.budget:g} s, {args.threads} threads, {args.res}² pixels) in its own `qsil compare` process, so "
             "a crash is recorded. Reference: central finite differences (`qsil reference --method fd`, "
             f"{args.ref_spp} spp, step h0·{args.ref_step_factor:g} where h0 is qsil's default step, which FD in "
             "the table uses: FD's blur of moving silhouettes is charged to it, not shared with the reference), "
             "which is itself biased by O(h²) and noisy: the z-score agreement test is a bias check of moderate "
             "power, not a proof.", "",
             f"Each method runs {args.repeats} times (seeds 0–{args.repeats - 1}). Each cell: non-finite pixels "
             "(must be 0, summed over the runs) / relative MSE vs the reference, the mean over the runs (the "
             "expected squared error; one run of a heavy-tailed estimator misjudges it both ways), with the "
             "runs' range in brackets / z = the runs' mean image-sum error over its combined standard error "
             "(|z| < 3: agrees) / zero-contribution rate of the boundary samples (mean spp reached per run). "
             "Machine: shared 2-core VM, timings noisy. The grids show the first run.", "",
             "The last column is the reference's relative noise floor over the best method's relative MSE: "
             "a reference can judge where it is ≤ 0.1 (marked **high** otherwise: the smallest errors there "
             "are partly the reference's).", "",
             "| scene | parameter | " + " | ".join(METHODS) + " | ref. floor / best |",
             "|---" * (len(METHODS) + 3) + "|"]
    for name, param, question, per in table:
        lines.append(f"| {name} | `{param}` | " + " | ".join(cell(per[m]) for m in METHODS) + f" | {floor_cell(per)} |")
    lines += ["", f"Whole study: {elapsed:.0f} s.", ""]
    for name, param, question, per in table:
        lines += [f"## {name}", "", question, ""]
        if os.path.exists(os.path.join(img_root, name, "grid.png")):
            lines += [f"![{name}](images/stability/{name}/grid.png)", ""]
    with open(os.path.join("docs", "stability.md"), "w") as f:
        f.write("\n".join(lines))


# The fields of a method's row kept in the study's record (results.json beside the grids).
RECORD_FIELDS = ("rel_mse", "rel_mse_runs", "z", "spp", "wall_seconds", "nonfinite_pixels", "zero_contribution_rate",
                 "rel_noise_floor")


def write_record(args, table, img_root, commit, date):
    """Writes IMG_ROOT/results.json, the study's table as data (tools/results_report.py judges issue 16's
    stability targets from it): the settings, the commit and date of the qsil that made it, and per scene
    its parameter and per method the RECORD_FIELDS of its row (or its error). Written whole or not at
    all (a temporary file renamed over it). Returns the record."""
    record = {"commit": commit, "date": date, "budget": args.budget, "repeats": args.repeats, "res": args.res,
              "ref_spp": args.ref_spp,
              "ref_step_factor": args.ref_step_factor, "threads": args.threads,
              "scenes": [{"name": name, "param": param,
                          "methods": {m: ({"error": per[m]["error"]} if "error" in per[m] else
                                          {f: per[m].get(f) for f in RECORD_FIELDS}) for m in METHODS}}
                         for name, param, _, per in table]}
    path = os.path.join(img_root, "results.json")
    os.makedirs(img_root, exist_ok=True)
    with open(path + ".tmp", "w") as f:
        json.dump(record, f, indent=1)
    os.replace(path + ".tmp", path)
    return record


def main():
    """Runs the study and writes docs/stability.md and its record, docs/images/stability/results.json."""
    ap = argument_parser(__doc__, res=48)
    ap.add_argument("--budget", type=float, default=2.0)
    ap.add_argument("--repeats", type=int, default=3,
                    help="runs per method (seeds 0 .. R-1), pooled: mean relative MSE, z of the mean sum")
    ap.add_argument("--ref-spp", type=int, default=32768)
    ap.add_argument("--ref-step-factor", type=float, default=0.25,
                    help="the reference's FD step over qsil's default step h0 (FD in the table uses h0)")
    ap.add_argument("--only", default="")
    ap.add_argument("--force-references", action="store_true",
                    help="re-render the FD references even where a cached one matches")
    args = ap.parse_args()
    if args.repeats < 1:
        sys.exit(f"stability_study: --repeats {args.repeats}: at least 1 run per method")
    args.qsil = os.path.abspath(args.qsil)
    # The grids need matplotlib in this interpreter: fail now, not after the study, with the last
    # study's grids left beside a new table.
    if subprocess.run([sys.executable, "-c", "import matplotlib"], stderr=subprocess.DEVNULL).returncode != 0:
        sys.exit(f"stability_study: {sys.executable} has no matplotlib (tools/install-deps.sh installs "
                 "python3-matplotlib for /usr/bin/python3)")
    os.chdir(ROOT)  # qsil gets repository-relative paths
    sdir = os.path.join("scenes", "stability")
    cases = [l.rstrip("\n").split("\t") for l in open(os.path.join(sdir, "params.txt")) if l.strip()]
    if args.only:
        keep = set(args.only.split(","))
        cases = [c for c in cases if c[0] in keep]
    work = os.path.join("out", "stability")
    img_root = os.path.join("docs", "images", "stability")
    os.makedirs(work, exist_ok=True)
    commit, date = git_commit(), time.strftime("%Y-%m-%d")  # of the qsil that renders
    started = time.time()
    table = []
    for name, param, question in cases:
        xml = os.path.join(sdir, name + ".xml")
        common = ["-D", f"res={args.res}", "--param", param, "--threads", str(args.threads)]
        ref = os.path.join(work, name + "-ref.exr")
        try:
            steps = [h * args.ref_step_factor
                     for h in default_steps(args.qsil, xml, [param], args.res, os.path.join(work, "h0.exr"))]
        except SystemExit as e:  # references.run's failure: record it like a failed reference
            table.append((name, param, question, {m: {"error": "reference step failed"} for m in METHODS}))
            print(f"{name}: {e}", flush=True)
            continue
        error = make_reference(args, xml, common, param, steps, ref)
        if error:
            table.append((name, param, question, {m: {"error": error} for m in METHODS}))
            continue
        per = run_methods(args, xml, common, ref, work, img_root, name)
        table.append((name, param, question, per))
        merge_images(per, work, img_root, name, param)
    elapsed = time.time() - started
    write_report(args, table, elapsed, img_root)
    if args.only:
        print("stability_study: --only: docs/images/stability/results.json is left as it was "
              "(it records whole studies)")
    else:
        write_record(args, table, img_root, commit, date)
    print(f"stability_study: docs/stability.md ({elapsed:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
