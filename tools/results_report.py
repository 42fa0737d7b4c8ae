#!/usr/bin/env python3
"""Regenerates docs/results.md: equal-time comparisons of the gradient methods on spot-mirror,
shadow-quad and direct, judged by independent finite-difference references (charts in
docs/images/compare/<scene>-<k>/).

Usage: python3 tools/references.py ...              # first: make or reuse the references
       python3 tools/results_report.py [--qsil PATH] [--res 256] [--budgets 4,15,60]
       [--k8-res 128] [--k8-budgets 2,8,15] [--k8-scenes LIST] [--threads 2] [--only NAMES]

For each scene: the cached FD reference of tools/references.py (out/references/index.json; the
report stops if it is missing), then `qsil compare` with quadric, vsphere, uniform and fd at each
budget (methods interleaved), whose plot_compare.py draws the charts; the same with eight
parameters (k8) on --k8-scenes. FD in the charts uses qsil's default step (what a user gets);
the reference uses the step its study chose. qsil runs in the repository root with
repository-relative paths, so results.csv/json carry no absolute paths.

Each section's record is committed beside its charts: docs/images/compare/<scene>-<k>/results.json
(the comparison) and reference.json (the reference's index entry, and the commit and date of the
qsil that made the comparison). With --only spot-mirror-k1,... only those sections are re-run; the
others are rebuilt from their committed records (an error if one is missing or was made at other
budgets or another resolution), so a change that leaves some scenes' images pixel-identical needs
only the affected scenes' references and comparisons (out/ is a cache, not a record).
"""
import argparse
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import time

from references import bias_upper_bound, floor_can_judge, git_commit

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = [("spot-mirror", "spot:translate:0,1,0"), ("shadow-quad", "object:translate:0,1,0"),
          ("direct", "spot:translate:1,0,0")]
METHODS = ["quadric", "vsphere", "uniform", "fd"]
# Why FD wins where it does: measured by hand (commands named), not by this script; update it with them.
WHY_FD_WINS = (
    "FD at the reference's own step (column `fd (ref. step)`) shares the reference's step bias, which no other "
    "method does, so its error is understated by up to that bias. Why FD at a good step still wins on "
    "`shadow-quad` (by 1.5×, within the target's 2×) and ties on `spot-mirror`, measured on 2026-11-25 with the "
    "constant interactions in doubles (`docs/architecture.md` §4; `python3 tools/bench/grad_cost.py --perf`, 256², "
    "16 spp, 2 threads): `grad` costs 5.3× (spot-mirror), 8.4× (shadow-quad) and 5.2× (direct) `render` per "
    "sample (earlier that day, before them and the splitting at fast shading points: 6.3×, 7.5× and 5.5×, and "
    "the day before 6.0×, 6.7× and 4.9×, so the machine's noise is about 10 %; 9.6×, 15.6× and 8.6× before the "
    "sample allocation: secondary boundary term at 0.5 traversals and primary at 0.25 samples per pixel sample), "
    "the boundary term 68–79 % of it, mostly importance (of nodes: LTC integrals over box outlines and bounding "
    "cones; of edges: LTC line integrals) and the rejection tests, 31–36 % of its traversals contributing "
    "nothing; Embree takes 9.6 %, 19.6 % and 14.6 % of the samples. And its per-pixel samples are heavy-tailed: on `shadow-quad` the secondary boundary term at points on "
    "the bunny, where a bunny edge millimetres away cuts the area light (a self-shadow penumbra far narrower "
    "than a pixel) and p, reached by a fixed direction at a grazing angle, slides fast (one such sample held 32 % "
    "of the per-pixel variance of 16 runs of 16 spp at 128², `docs/design-notes.md`, \"Narrow self-shadow "
    "penumbrae\"; since 2026-11-25 the light contour sets find those edges, `docs/architecture.md` §5, and what "
    "remains of that tail is the slide, whose share at one vertex the splitting at fast shading points divides), and the interior term along the bunny's outline; on `spot-mirror` the interior term at hits "
    "on Spot at grazing angles through the mirror, about half its variance since the contour sets "
    "(\"Interior-term tails at grazing hits\"): both tails belong to the parametrization (directions fixed), "
    "while FD with common random numbers subtracts two almost equal renders of a scene that is "
    "smooth in θ. Where the quadric method wins: `direct`, where FD at a step small enough not to blur Spot's "
    "outline is noisy (the quadric method's interior tails there were cut by the defensive mixture for "
    "derivative paths, `docs/design-notes.md`), and with several parameters (eight, where FD "
    "pays 16 renders per sample): ahead on all three scenes, by 4.4× on `shadow-quad` (against a reference of "
    "8170 spp, whose floor is below 1/10 of quadric's error, with the constant interactions in doubles, which made "
    "`grad` at k = 8 there 1.38× faster at equal output in an interleaved A/B, `docs/architecture.md` §4, while in "
    "this run FD at h0 and at h0/8, equal in cost per sample, got 134 and 165 spp in the same 15 s: the machine's "
    "noise is as large as the gain; 4.3× before it against a reference of 7995 spp; against the earlier 4070-spp one, at "
    "least 3.6× (est. 4.1) with the splitting at fast shading points and at least 3.4× (est. 3.8) before it; 3.1× "
    "(est. 3.4) before the light contour sets, 2.0× before the smooth-crease weight, 1.6× before the choice among "
    "the non-split candidates was made afresh, "
    "`docs/architecture.md` §5 \"Splitting\"), at least 7.5× on `direct` and at least 4.2× on `spot-mirror` "
    "(bounds: those references' floors are above 1/10 of quadric's errors). Until 2026-11-24 FD's default step for rotations and scales was 10⁻³ rad / 10⁻³, which "
    "moved the bunny 35–43× and Spot 7–12× less than a translation's h0, so FD on those parameters was that many "
    "times noisier and the k = 8 ratios were overstated (shadow-quad 7.7× then); h0 now moves every kind's "
    "fastest vertex by 10⁻³ of the scene's diagonal. FD's weaknesses: 2k renders for k "
    "parameters, and a step per scene (`docs/gradient-checks.md`, \"The FD step at pixel scale\").")
FD_REF = "fd (ref. step)"  # FD at the reference's step, where the step study chose one below h0


def run(cmd):
    """Runs a command in the repository root, echoing it; raises on failure."""
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, cwd=ROOT)


def cpu_model():
    """The CPU model name from /proc/cpuinfo."""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def compare_run(args, d, entry, budgets, cmd):
    """Runs `qsil compare` (`cmd`, writing into `d`), or with --reuse keeps d's earlier results.json when
    it was made against the same reference (file, spp and steps, kept in d/reference.json) and budgets.
    Returns (results.json, whether it was reused, the commit and date of the qsil that made it: git_commit()
    when the run starts, kept in d/made_by.json; "unknown" for a reused comparison without that file)."""
    done = os.path.join(ROOT, d, "results.json")
    key_path = os.path.join(ROOT, d, "reference.json")
    made_by_path = os.path.join(ROOT, d, "made_by.json")
    key = {"file": entry["file"], "spp": entry["spp"], "steps": entry["steps"]}
    if args.reuse and os.path.exists(done) and os.path.exists(key_path):
        old = json.load(open(done))
        if json.load(open(key_path)) == key and old["targets"] == [float(b) for b in budgets.split(",")]:
            print(f"results_report: reusing {d}/results.json", flush=True)
            made_by = (json.load(open(made_by_path)) if os.path.exists(made_by_path)
                       else {"commit": "unknown", "date": "unknown"})
            return old, True, made_by
    made_by = {"commit": git_commit(), "date": time.strftime("%Y-%m-%d")}
    run(cmd)
    for path, data in ((key_path, key), (made_by_path, made_by)):
        with open(path, "w") as f:
            json.dump(data, f)
    return json.load(open(done)), False, made_by


def compare(args, scene, kset, res, budgets, entry):
    """Runs `qsil compare` for one scene and parameter set against its reference (or reuses it,
    compare_run); returns results.json and the commit and date of the qsil that made it."""
    xml = os.path.join("scenes", scene + ".xml")
    name = f"{scene}-{kset}"
    d = os.path.join("out", "results", name)
    cmd = [args.qsil, "compare", xml, "-D", f"res={res}", *sum((["--param", p] for p in entry["params"]), []),
           "--threads", str(args.threads), "--methods", ",".join(METHODS), "--budgets", budgets,
           "--reference", entry["file"], "-q", "--out", d]
    os.environ.setdefault("QSIL_PYTHON", sys.executable)  # compare draws its charts with this python
    result, reused, made_by = compare_run(args, d, entry, budgets, cmd)
    if reused and not os.path.exists(os.path.join(ROOT, d, "grid.png")):
        run([sys.executable, os.path.join("tools", "plot_compare.py"), d])
    copy_charts(d, name)
    return result, made_by


def compare_fd_at_reference_step(args, scene, kset, res, budgets, entry):
    """FD at the reference's own step (when the step study chose one below h0), charged alike: its
    rows as FD_REF, or [] when the reference uses h0. Not in the charts (one FD per `qsil compare`)."""
    if entry["step_study"].get("chosen_factor", 1) == 1:
        return []
    xml = os.path.join("scenes", scene + ".xml")
    d = os.path.join("out", "results", f"{scene}-{kset}-fd-ref-step")
    cmd = [args.qsil, "compare", xml, "-D", f"res={res}", *sum((["--param", p] for p in entry["params"]), []),
           "--threads", str(args.threads), "--methods", "fd", "--budgets", budgets, "--reference", entry["file"],
           *sum((["--h", f"{h:.9g}"] for h in entry["steps"]), []), "-q", "--no-plot", "--out", d]
    rows = compare_run(args, d, entry, budgets, cmd)[0]["rows"]
    for r in rows:
        r["method"] = FD_REF
    return rows


def largest_budget_rows(res_json):
    """A comparison's rows at its largest budget that have a relative MSE, by method."""
    last = max(res_json["targets"])
    return {r["method"]: r for r in res_json["rows"] if r["target"] == last and r["rel_mse"] is not None}


def record_dir(name):
    """docs/images/compare/NAME: a section's committed charts and records."""
    return os.path.join(ROOT, "docs", "images", "compare", name)


def copy_charts(d, name):
    """Copies a comparison's charts and data into docs/images/compare/NAME/."""
    dst = record_dir(name)
    os.makedirs(dst, exist_ok=True)
    for f in ("error_vs_time.png", "grid.png", "results.csv", "results.json"):
        shutil.copy(os.path.join(ROOT, d, f), os.path.join(dst, f))


def write_record(name, entry, fd_ref_rows, made_by):
    """Writes docs/images/compare/NAME/reference.json: the section's reference record (the index entry
    of tools/references.py), the rows of FD at the reference's step (not in results.json: a comparison
    of its own) and `made_by`, the commit and date of the qsil that made the comparisons (compare_run).
    Returns the record."""
    dst = record_dir(name)
    record = dict(entry, fd_ref_step_rows=fd_ref_rows, comparison=made_by)
    with open(os.path.join(dst, "reference.json.tmp"), "w") as f:
        json.dump(record, f, indent=1)
    os.replace(os.path.join(dst, "reference.json.tmp"), os.path.join(dst, "reference.json"))
    return record


def kept_section(name, res, budgets):
    """A section not re-run (--only): (reference record, results.json) from docs/images/compare/NAME/.
    Raises SystemExit when a record is missing or was made at another resolution or other budgets."""
    paths = [os.path.join(record_dir(name), f) for f in ("reference.json", "results.json")]
    missing = [p for p in paths if not os.path.exists(p)]
    if missing:
        raise SystemExit(f"results_report: {os.path.relpath(missing[0], ROOT)} is missing; re-run section {name} "
                         "(leave it out of --only's list, or add it)")
    entry, res_json = (json.load(open(p)) for p in paths)
    res_json["rows"] += entry.get("fd_ref_step_rows", [])
    if res_json["resolution"] != [res, res] or res_json["targets"] != [float(b) for b in budgets.split(",")]:
        raise SystemExit(f"results_report: docs/images/compare/{name} was made at {res_json['resolution'][0]}², "
                         f"budgets {res_json['targets']}, not {res}², budgets {budgets}; re-run it too (--only)")
    return entry, res_json


def per_pixel_study(entry):
    """Whether a reference's step study compared steps per pixel too (not only by 8x8 blocks)."""
    return all("agree_pixels" in p for p in entry["step_study"]["pairs"])


def reference_text(entry, res_json):
    """One paragraph: how the reference was made and whether it can judge."""
    study = entry["step_study"]
    per_pixel = per_pixel_study(entry)

    def pair_text(p):
        if not per_pixel:
            return f"h0·{p['h_factor']:g} vs h0·{p['smaller_factor']:g}: {'agree' if p['agree'] else 'DIFFER'}"
        return (f"h0·{p['h_factor']:g} vs h0·{p['smaller_factor']:g}: blocks {'agree' if p['agree_blocks'] else 'DIFFER'}, "
                f"pixels {'agree' if p['agree_pixels'] else 'DIFFER'}, excess {p['excess_rel_mse']:.3g}"
                + (f" ± {p['excess_se']:.2g}" if "excess_se" in p else ""))
    pairs = "; ".join(pair_text(p) for p in study["pairs"])
    if per_pixel:
        bias, bias_se = study.get("step_bias_rel"), study.get("step_bias_se")
        bound = entry["key"].get("max_step_bias", 0.01)
        if bias is None or bias_se is None:
            se_text = " (its standard error was not recorded)" if bias is not None else ""
        elif bias_upper_bound(bias, bias_se) <= bound:
            se_text = f" ± {bias_se:.2g} (s.e.; within the bound {bound:g} with 97.7 % confidence)"
        else:
            se_text = (f" ± {bias_se:.2g} (s.e.; chosen by the estimate alone, before the study bounded it by "
                       f"|excess| + 2 s.e.: that upper bound, {bias_upper_bound(bias, bias_se):.2g}, exceeds {bound:g})")
        bias_text = (f"Step bias (per-pixel squared difference from h0/8 beyond noise, × mean square): "
                     f"{bias:.3g}{se_text}. " if bias is not None else
                     "The step is the study's smallest, h0/8 (no larger step was within the bias bound); its own "
                     "bias is not measured (about 1/4 of h0/4's excess if it halves like the larger steps'). ")
    else:
        bias_text = ("**This reference predates the per-pixel step study**: its step was chosen by 8×8 block tests "
                     "alone, which cannot see the blur of a step whose silhouettes move about a pixel (on `direct` "
                     "and `shadow-quad` the excess of h0 over h0/8 was 0.51 and 0.80 × the mean square at 256 spp); its step bias is not "
                     "known, and FD at the same step shares it, so FD's error here is understated. ")
    last = max(res_json["targets"])
    best = min((r["rel_mse"] for r in largest_budget_rows(res_json).values() if r["rel_mse"]), default=float("nan"))
    floor = entry["rel_noise_floor"]
    ok = floor_can_judge(floor, best)
    qc = entry["quadric_check"]
    return (f"Reference: FD with common random numbers, {entry['spp']} spp, step h = "
            f"{', '.join(f'{h:.4g}' for h in entry['steps'])} (h0·{study['chosen_factor']:g}), "
            f"{entry['seconds']:.0f} s, relative noise floor {floor:.3g} — "
            f"{'≤' if ok else '**above**'} 1/10 of the best method's relative MSE at {last:g} s ({best:.3g})"
            f"{'' if ok else ': the smallest errors here are partly the reference’s'}. "
            f"Step study ({study['runs'][0]['spp']} spp each): {pairs}. {bias_text}Independence check at "
            f"{qc['res']}², {qc['spp']} spp each: quadric and FD {'agree' if qc['agree'] else '**disagree**'} "
            f"({qc['stats']}).{unseen_text(qc)}")


def unseen_text(qc):
    """Where a disagreeing independence check passes without the blocks one reference never sampled
    (`qsil agree`'s diagnostic), says so."""
    m = re.search(r"(\d+) tests of blocks one reference never sampled \(chi2/dof ([0-9.]+) without them, "
                  r"limit ([0-9.]+)\)", qc["stats"])
    if qc["agree"] or not m or int(m.group(1)) == 0 or not 0 < float(m.group(2)) <= float(m.group(3)):
        return ""
    sums = [float(z) for z in re.findall(r"image sum: .*?, z (-?[0-9.]+)", qc["stats"])]
    if not sums or max(abs(z) for z in sums) > 3:
        return ""
    return (f" The disagreement is confined to the {m.group(1)} block tests where one reference never sampled "
            f"the block (every pixel 0 with s.e. 0, as FD at a small step leaves a rare event's region): their z "
            f"tests the other against 0, not against a reference that saw the block; without them χ²/dof is "
            f"{m.group(2)} (limit {m.group(3)}), and every image sum agrees.")


def ratio_cell(a, b, floor):
    """One efficiency ratio of the targets table: relative MSEs a (the other method) over b (quadric),
    both measured against a reference whose own relative noise floor is `floor` (each measured MSE is
    the method's plus the floor). Where the floor is at most 1/10 of the smaller of a, b, the ratio of
    the methods' own errors, (a - floor) / (b - floor). Otherwise that estimate is too uncertain to
    judge a target, and the cell gives the bound the raw ratio a / b is: subtracting a common
    floor 0 <= floor < min(a, b) moves a ratio away from 1, so (a - f) / (b - f) >= a / b when
    a >= b and <= a / b when a < b; the floor-subtracted estimate follows in parentheses.
    Returns the cell's text, e.g. "3.15", "≥ 5.5 (est. 391)", "≤ 0.8 (est. 0.4)"."""
    own = max(a - floor, 1e-12) / max(b - floor, 1e-12)
    if floor_can_judge(floor, min(a, b)):
        return f"{own:.3g}"
    raw = a / b
    return f"{'≥' if raw >= 1 else '≤'} {raw:.3g} (est. {own:.3g})"


def targets_text(results):
    """The efficiency targets (quadric against FD, vsphere and uniform at the largest budget, the
    references' floors subtracted) and why finite differences win where they do."""
    lines = ["## Targets", "",
             "Ratios of relative MSE at the largest budget with the reference's floor subtracted (the "
             "methods' own error); equal time, so a ratio is an efficiency ratio. Where the floor is above 1/10 "
             "of either error compared, the floor-subtracted ratio is too uncertain to judge a target and the "
             "cell gives the bound the ratio with the floor included is (a common floor moves a ratio away "
             "from 1: ≥ when the other method's error is the larger, ≤ otherwise), then the estimate.", "",
             "| scene | k | best FD / quadric | vsphere / quadric | uniform / quadric | target |", "|---|---|---|---|---|---|"]
    for (scene, kset), (entry, res) in results.items():
        floor = entry["rel_noise_floor"]
        rel = {m: r["rel_mse"] for m, r in largest_budget_rows(res).items()}
        q = rel.get("quadric")
        if not q:
            continue
        k = len(entry["params"])
        if FD_REF in rel:
            rel["fd"] = min(rel["fd"], rel[FD_REF]) if "fd" in rel else rel[FD_REF]
        f = lambda m: ratio_cell(rel[m], q, floor) if m in rel else "–"
        goal = "FD / quadric ≥ 1 (≥ 0.5 on shadow-quad)" if k == 1 else "FD / quadric ≥ 5"
        lines.append(f"| {scene} | {k} | {f('fd')} | {f('vsphere')} | {f('uniform')} | {goal}; vsphere ≥ 10 with secondary silhouettes; uniform ≥ 1 |")
    old_refs = any(not per_pixel_study(entry) for entry, _ in results.values())
    steps = []
    for (scene, kset), (entry, res) in results.items():
        rel = {m: r["rel_mse"] for m, r in largest_budget_rows(res).items()}
        if "fd" in rel and FD_REF in rel:
            steps.append(f"{scene}{' (k = 8)' if len(entry['params']) > 1 else ''} {rel['fd']:.3g} at h0, "
                         f"{rel[FD_REF]:.3g} at h0·{entry['step_study']['chosen_factor']:g}")
    lines += ["", "Where best FD / quadric is below its target, finite differences at a well-chosen step are the "
              "more efficient estimator today. The step matters: at qsil's default step h0 the silhouettes move "
              "about two pixels over 2h at 256², which blurs the derivative image; a smaller step avoids the blur "
              "at the price of variance ∝ 1/h where silhouettes cross pixels, so the best step depends on the "
              "scene and the budget (FD's relative MSE at the largest budget: " + "; ".join(steps) + "). "
              + ("References made before the per-pixel study (flagged below) share FD's h0 blur, so there FD's "
                 "error is understated and the quadric method's overstated. " if old_refs else "")
              + WHY_FD_WINS, ""]
    return lines


def main():
    """Runs the comparisons and writes docs/results.md."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--qsil", default=os.path.join(ROOT, "build", "qsil"))
    ap.add_argument("--budgets", default="4,15,60")
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--k8-budgets", default="2,8,15")
    ap.add_argument("--k8-res", type=int, default=128)
    ap.add_argument("--k8-scenes", default="spot-mirror,shadow-quad,direct")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reuse", action="store_true",
                    help="keep earlier comparisons against the same reference and budgets (out/results/)")
    ap.add_argument("--only", default="",
                    help="re-run only these sections (e.g. spot-mirror-k1,spot-mirror-k8); the others come from "
                         "their committed records in docs/images/compare/")
    args = ap.parse_args()
    args.qsil = os.path.abspath(args.qsil)
    index_path = os.path.join(ROOT, "out", "references", "index.json")
    index = json.load(open(index_path)) if os.path.exists(index_path) else {}
    jobs = [(scene, "k1", args.res, args.budgets) for scene, _ in SCENES]
    jobs += [(scene, "k8", args.k8_res, args.k8_budgets) for scene in args.k8_scenes.split(",") if scene]
    only = [n for n in args.only.split(",") if n]
    unknown = sorted(set(only) - {f"{scene}-{kset}" for scene, kset, _, _ in jobs})
    if unknown:
        raise SystemExit(f"results_report: --only names no section {', '.join(unknown)} (sections: "
                         f"{', '.join(f'{scene}-{kset}' for scene, kset, _, _ in jobs)})")
    started = time.time()
    results = {}
    kept = {}
    for scene, kset, res, budgets in jobs:
        if only and f"{scene}-{kset}" not in only:
            kept[(scene, kset)] = kept_section(f"{scene}-{kset}", res, budgets)
    for scene, kset, res, budgets in jobs:
        if (scene, kset) in kept:
            results[(scene, kset)] = kept[(scene, kset)]
            continue
        entry = index.get(f"{scene}-{kset}-{res}")
        if not entry:
            raise SystemExit(f"results_report: no reference {scene}-{kset}-{res} in {index_path}; run "
                             f"python3 tools/references.py --scenes {scene} --params {kset} --res {res}")
        res_json, made_by = compare(args, scene, kset, res, budgets, entry)
        fd_ref_rows = compare_fd_at_reference_step(args, scene, kset, res, budgets, entry)
        res_json["rows"] += fd_ref_rows
        results[(scene, kset)] = (write_record(f"{scene}-{kset}", entry, fd_ref_rows, made_by), res_json)
    elapsed = time.time() - started
    render_seconds = sum(r["wall_seconds"] for key, (_, res) in results.items() if key not in kept
                         for r in res["rows"])
    made_by = "; ".join(f"{scene}, k = {len(entry['params'])}: {entry['comparison']['commit']} "
                        f"({entry['comparison']['date']})" for (scene, _), (entry, _) in results.items()
                        if "comparison" in entry)

    lines = ["# Equal-time comparisons", "",
             "Generated by `tools/results_report.py` from the references of `tools/references.py` (do not edit "
             "by hand). Each method renders the gradient progressively (sample passes, fresh seed per pass) until "
             "its wall-clock budget; methods are interleaved per budget so machine noise hits all alike. Error is "
             "measured against an **independent reference: central finite differences with common random "
             "numbers**, at a step chosen by a step study (the largest of h0, h0/2, h0/4, h0/8 that agrees with "
             "every smaller one under `qsil agree`'s image-sum, 8×8 block and per-pixel z-tests and whose "
             "per-pixel squared difference from h0/8 is at most 0.01 × the mean square with 97.7 % confidence, |excess| + 2 s.e.; a step whose silhouettes "
             "move about a pixel blurs the derivative image, which block tests cannot see), over every pixel and derivative "
             "channel; relative MSE = MSE / mean(reference²). The dashed line is the reference's own noise floor "
             "(mean of its squared per-pixel standard errors): a measured MSE is the method's plus the floor. "
             "FD in the charts uses qsil's default step h0 and is charged for its 2k renders (k parameters); where "
             "the reference's step is smaller, FD at that step runs too (column `fd (ref. step)`, not in the "
             "charts), and the ratios take the better of the two FDs.", "",
             f"Machine: {cpu_model()}, {os.cpu_count()} hardware threads, {args.threads} render threads, shared "
             "with other jobs (**timings are noisy**: treat ratios within a factor ~1.5 as ties). "
             f"k = 1: {args.res}², budgets {args.budgets} s; k = 8: {args.k8_res}², budgets {args.k8_budgets} s; "
             f"this run's comparisons took {render_seconds:.0f} s of renders (summed over methods and budgets; "
             "comparisons reused with --reuse were made by earlier runs"
             + (f"; sections kept from earlier runs: {', '.join(f'{s}-{k}' for s, k in kept)}" if kept else "")
             + "). " + (f"Commit (and date) of the qsil that made each section's comparisons: {made_by}." if made_by
                        else ""), ""]
    lines += ["## Relative MSE at the largest budget", "",
              "| scene | k | " + " | ".join(METHODS + [FD_REF]) + " | best fd / quadric | vsphere / quadric | uniform / quadric "
              "| ref. floor |", "|---" * (len(METHODS) + 7) + "|"]
    for (scene, kset), (entry, res) in results.items():
        rel = largest_budget_rows(res)
        cells = [f"{rel[m]['rel_mse']:.3g} ({rel[m]['spp']} spp)" if m in rel else "–" for m in METHODS + [FD_REF]]
        q = rel.get("quadric", {}).get("rel_mse")
        ratio = lambda m: f"{rel[m]['rel_mse'] / q:.3g}" if q and m in rel else "–"
        best_fd = min(("fd", FD_REF), key=lambda m: rel[m]["rel_mse"] if m in rel and rel[m]["rel_mse"] else 1e300)
        lines.append(f"| {scene} | {len(entry['params'])} | " + " | ".join(cells) +
                     f" | {ratio(best_fd)} | {ratio('vsphere')} | {ratio('uniform')} | {entry['rel_noise_floor']:.3g} |")
    lines.append("")
    lines += targets_text(results)
    for (scene, kset), (entry, res) in results.items():
        name = f"{scene}-{kset}"
        params = ", ".join(f"`{p}`" for p in entry["params"])
        lines += [f"## {scene}, k = {len(entry['params'])} ({params})", "", reference_text(entry, res), "",
                  f"![error vs time](images/compare/{name}/error_vs_time.png)", "",
                  f"![grid](images/compare/{name}/grid.png)", "",
                  f"Data: [results.csv](images/compare/{name}/results.csv).", ""]
    with open(os.path.join(ROOT, "docs", "results.md.tmp"), "w") as f:
        f.write("\n".join(lines))
    os.replace(os.path.join(ROOT, "docs", "results.md.tmp"), os.path.join(ROOT, "docs", "results.md"))
    print(f"results_report: docs/results.md ({elapsed:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
