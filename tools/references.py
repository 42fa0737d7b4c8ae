#!/usr/bin/env python3
"""Makes (or reuses) the independent references that docs/results.md judges against.

Usage: python3 tools/references.py [--qsil build/qsil] [--res 256] [--seconds 600]
       [--scenes spot-mirror,shadow-quad,direct] [--params k1|k8] [--force]

For each chart scene and parameter set, three steps, each logged and recorded:

1. Step study. Central finite differences with common random numbers (`qsil reference --method
   fd`) at steps h0, h0/2, h0/4, h0/8 (h0: qsil's default step, 1e-3 of the scene's diagonal for
   translations), at the chart resolution, independent seeds. `qsil agree` compares each step
   with every smaller one, with 8x8 blocks and per pixel (--block 1): image-sum, block and pixel
   z-tests. The chosen step is the largest h whose image agrees with all of them in both. The
   per-pixel test is the one that matters: a step whose silhouettes move about a pixel blurs the
   derivative image along the motion, which block sums hide (h0 on `direct` moved Spot's outline
   2.2 pixels: the 8x8 test agreed with h0/8, and the blur was 0.51 of the images' mean square;
   the per-pixel z-test refused it at 256 spp, chi2/dof 1.43 against a limit of 1.27, but not at
   128 spp, 1.23, so the excess bound below is what decides). Every pair's per-pixel squared difference beyond noise
   (`qsil agree`'s excess, relative to the images' mean square, with its standard error) is
   recorded, and the chosen step must also be within --max-step-bias of the smallest with 97.7 %
   confidence, |excess| + 2 s.e. <= bound (the z-tests' slack lets a blur of 0.08 x the mean square
   through; a noisy excess estimate alone can pass anything, and one far below its true value's
   floor of 0 shows an s.e. too small for heavy-tailed noise: shadow-quad's eight parameters at 64
   spp gave -0.147 +- 0.037 for h0/2); a study whose renders are too noisy to bound the excess
   therefore falls to the smallest step, h0/8 (its own bias is
   then not measured; on `direct` and `shadow-quad` the excess fell about 4x per halving: 0.51,
   0.082, 0.011 for h0, h0/2, h0/4 against h0/8 on `direct` at 256 spp).
2. Reference. FD at the chosen step with as many spp as fit in --seconds (from the study's time
   per spp), 2 threads, written to out/references/<scene>-<params>.exr with its record. It is
   cached: rerunning with the same scene files, parameters, resolution, step and spp reuses it
   (--force recomputes).
3. Independence check. At 64x64 the quadric method at high spp (`qsil reference --method
   quadric`) must agree with FD at the chosen step (`qsil agree`); a disagreement is a bug to find
   and is recorded as such (the charts then say so). After a change to the estimator,
   --recheck-quadric re-renders the quadric half of a cached reference's check and re-judges it
   (the reference and the FD half do not depend on the estimator).

Writes out/references/index.json: per reference its file, spp, step, seconds, relative noise
floor (mean se^2 / mean ref^2), the step study and the agreement check. tools/results_report.py
reads it. qsil runs in the repository root with repository-relative paths.
"""
import argparse
import hashlib
import json
import os
import platform
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join("out", "references")  # relative to ROOT

# Chart scenes: one parameter (k1) and eight (k8: translations, rotations, a scale, a vertex).
SCENES = {
    "spot-mirror": ("spot", "spot:translate:0,1,0"),
    "shadow-quad": ("object", "object:translate:0,1,0"),
    "direct": ("spot", "spot:translate:1,0,0"),
}


def argument_parser(doc, res, threads=2):
    """The command line every study and benchmark script starts from: its docstring as the help,
    --qsil (the program, default build/qsil), --res (image side, default `res`) and --threads."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--qsil", default=os.path.join(ROOT, "build", "qsil"))
    ap.add_argument("--res", type=int, default=res)
    ap.add_argument("--threads", type=int, default=threads)
    return ap


def param_set(scene, which):
    """The --param specs of a chart scene: k1 (the chart parameter) or k8 (eight parameters)."""
    shape, first = SCENES[scene]
    if which == "k1":
        return [first]
    rest = [f"{shape}:translate:1,0,0", f"{shape}:translate:0,1,0", f"{shape}:translate:0,0,1",
            f"{shape}:rotate:1,0,0", f"{shape}:rotate:0,1,0", f"{shape}:rotate:0,0,1", f"{shape}:scale",
            f"{shape}:vertex:0:0,1,0"]
    return [first] + [p for p in rest if p != first][:7]


def run(cmd, check=True):
    """Runs a qsil command in the repository root; returns (exit code, stdout, seconds)."""
    print("+", " ".join(cmd), flush=True)
    t = time.time()
    p = subprocess.run(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    sys.stdout.write(p.stdout)
    sys.stderr.write(p.stderr)  # its warnings too (a reference one pixel carries, cli_common.h)
    if check and p.returncode != 0:
        raise SystemExit(f"references: command failed with exit code {p.returncode}: {' '.join(cmd)}")
    return p.returncode, p.stdout, time.time() - t


def git_commit():
    """The repository's HEAD commit (short; "unknown" outside a git checkout), with "+" when a tracked
    file outside docs/ (what the reports write) differs from it: the commit of the qsil that renders."""
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".", ":!docs"], cwd=ROOT,
                           capture_output=True, text=True)
    return (head.stdout.strip() or "unknown") + ("+" if dirty.stdout.strip() else "")


def cpu_model():
    """The CPU model name from /proc/cpuinfo ("unknown" where it cannot be read)."""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def scene_digest(xml):
    """sha256 of the scene file and of every file it names (meshes, env maps)."""
    h = hashlib.sha256()
    path = os.path.join(ROOT, xml)
    text = open(path, "rb").read()
    h.update(text)
    for name in sorted(set(re.findall(rb'value="([^"]+\.(?:obj|exr))"', text))):
        f = os.path.join(os.path.dirname(path), name.decode())
        if os.path.exists(f):
            h.update(open(f, "rb").read())
    return h.hexdigest()


def default_steps(qsil, xml, params, res, image=os.path.join(OUT, "h0.exr")):
    """qsil's default FD step h0 per parameter (printed by a 1-spp `qsil fd` run writing `image`,
    relative to ROOT, whose folder must exist)."""
    _, out, _ = run([qsil, "fd", xml, "-D", f"res={res}", *sum((["--param", p] for p in params), []), "--spp", "1",
                     "-q", "-o", image])
    return [float(x) for x in re.findall(r"h\d+ = ([0-9.eE+-]+)", out)]


def reference(qsil, xml, params, res, method, spp, seed, path, steps=None, threads=2):
    """Renders a `qsil reference`; returns (seconds, relative noise floor)."""
    cmd = [qsil, "reference", xml, "-D", f"res={res}", *sum((["--param", p] for p in params), []),
           "--method", method, "--spp", str(spp), "--seed", str(seed), "--threads", str(threads), "-q", "-o", path]
    for h in steps or []:
        cmd += ["--h", f"{h:.9g}"]
    _, out, seconds = run(cmd)
    m = re.search(r"= ([0-9.eE+-]+) x mean\(ref\^2\)", out)
    return seconds, float(m.group(1)) if m else float("nan")


def quadric_check(qsil, xml, params, spp, name):
    """Renders the quadric half of a reference's 64x64 independence check (seed 11) to its cached path;
    returns the path."""
    path = os.path.join(OUT, f"{name}-check-quadric.exr")
    reference(qsil, xml, params, 64, "quadric", spp, 11, path)
    return path


def agree(qsil, a, b, block=8):
    """`qsil agree A B --block N`: (agrees, the statistics line, excess relative MSE, its standard error)."""
    code, out, _ = run([qsil, "agree", a, b, "--block", str(block)], check=False)
    if code not in (0, 1):
        raise SystemExit(f"references: qsil agree {a} {b} failed (exit {code})")
    stats = " ".join(l.strip() for l in out.splitlines()[1:-1])
    m = re.search(r"beyond noise: ([0-9.eE+-]+|nan|inf) \+- ([0-9.eE+-]+|nan|inf) x mean square", out)
    return code == 0, stats, float(m.group(1)) if m else float("nan"), float(m.group(2)) if m else float("nan")


def write_index(index, path):
    """Writes the index whole or not at all (a temporary file renamed over it)."""
    with open(path + ".tmp", "w") as f:
        json.dump(index, f, indent=1)
    os.replace(path + ".tmp", path)


# A reference can judge an error when its relative noise floor is at most this share of it (the issue's
# "noise floor <= 1/10 of the errors compared"); results_report and stability_study flag the rest.
JUDGE_FLOOR_SHARE = 0.1


def floor_can_judge(floor, rel_mse):
    """Whether a reference with relative noise floor `floor` can judge a relative MSE `rel_mse` (both
    relative to the reference's mean square): floor <= JUDGE_FLOOR_SHARE * rel_mse."""
    return floor <= JUDGE_FLOOR_SHARE * rel_mse


def bias_upper_bound(excess, se):
    """What the step study holds against --max-step-bias: |excess| + 2 s.e. (97.7 % upper bound of a
    quantity >= 0; an estimate far below 0 means an s.e. made too small by heavy tails, see step_study)."""
    return abs(excess) + 2 * se


def step_study(qsil, xml, params, res, spp, name, max_bias):
    """FD at h0, h0/2, h0/4, h0/8 and the agreement (8x8 blocks and per pixel) of each with every smaller
    step; returns the record."""
    h0 = default_steps(qsil, xml, params, res)
    factors = [1, 0.5, 0.25, 0.125]
    runs = []
    for i, f in enumerate(factors):
        path = os.path.join(OUT, f"{name}-step{i}.exr")
        seconds, floor = reference(qsil, xml, params, res, "fd", spp, 1000 + i, path, [h * f for h in h0])
        runs.append({"factor": f, "steps": [h * f for h in h0], "spp": spp, "seconds": seconds,
                     "rel_noise_floor": floor, "file": path})
    pairs = []
    for i, a in enumerate(runs):
        for b in runs[i + 1:]:
            ok8, stats8, _, _ = agree(qsil, a["file"], b["file"], 8)
            ok1, stats1, excess, excess_se = agree(qsil, a["file"], b["file"], 1)
            pairs.append({"h_factor": a["factor"], "smaller_factor": b["factor"], "agree": ok8 and ok1,
                          "agree_blocks": ok8, "agree_pixels": ok1, "excess_rel_mse": excess,
                          "excess_se": excess_se, "stats": stats8 + " " + stats1})
    # The largest step that agrees with every smaller one (the smallest has nothing to agree with)
    # and whose squared difference from the smallest is at most max_bias: the z-tests' slack
    # (chi2/dof limit 1 + 5 sqrt(2/dof) + 0.25) lets through a blur of 0.08 x the mean square (h0/2
    # on `direct` at 256 spp), so the excess is bounded too, by its one-sided 97.7 % upper bound
    # (excess + 2 s.e.): the estimate alone passed h0 on shadow-quad's eight parameters at 64 spp
    # (-0.056, noise-dominated). The true excess is >= 0, so an estimate far below 0 means the
    # heavy-tailed per-pixel noise made its s.e. too small (h0/2 there: -0.147 +- 0.037): |excess|
    # is bounded, not excess. Without such a step, the smallest.
    def to_smallest(f):
        return next(p for p in pairs if p["h_factor"] == f and p["smaller_factor"] == factors[-1])

    def within_bound(f):
        p = to_smallest(f)
        return bias_upper_bound(p["excess_rel_mse"], p["excess_se"]) <= max_bias
    chosen = next((r["factor"] for r in runs[:-1]
                   if all(p["agree"] for p in pairs if p["h_factor"] == r["factor"]) and within_bound(r["factor"])),
                  factors[-1])
    # The chosen step's bias against the smallest (the smallest's own: not measured).
    last = to_smallest(chosen) if chosen != factors[-1] else None
    bias = last["excess_rel_mse"] if last else None
    bias_se = last["excess_se"] if last else None
    return {"h0": h0, "runs": runs, "pairs": pairs, "chosen_factor": chosen, "step_bias_rel": bias,
            "step_bias_se": bias_se, "steps": [h * chosen for h in h0],
            "seconds_per_spp": sum(r["seconds"] for r in runs) / len(runs) / spp}


def main():
    """Makes or reuses every reference and writes out/references/index.json."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--qsil", default=os.path.join(ROOT, "build", "qsil"))
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--seconds", type=float, default=600, help="time of each reference render")
    ap.add_argument("--study-spp", type=int, default=128,
                    help="spp of each step-study render (128: the setting docs/results.md is made with)")
    ap.add_argument("--spp", type=int, default=0, help="spp of the reference (instead of filling --seconds)")
    ap.add_argument("--check-spp", type=int, default=4096, help="spp of the 64x64 independence check (each method)")
    ap.add_argument("--max-step-bias", type=float, default=0.01,
                    help="largest per-pixel squared difference (x mean square) of the chosen FD step from h0/8")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--params", default="k1", choices=["k1", "k8"])
    ap.add_argument("--force", action="store_true", help="recompute cached references")
    ap.add_argument("--recheck", action="store_true",
                    help="only re-judge the independence check of cached references with the current `qsil agree` "
                         "(never renders; an error when the options match no cached reference)")
    ap.add_argument("--recheck-quadric", action="store_true",
                    help="re-render the quadric half of the independence check of cached references with the "
                         "current qsil, then re-judge it (after a change to the estimator: the FD reference and "
                         "its check do not depend on it)")
    args = ap.parse_args()
    qsil = os.path.abspath(args.qsil)
    os.makedirs(os.path.join(ROOT, OUT), exist_ok=True)
    index_path = os.path.join(ROOT, OUT, "index.json")
    index = json.load(open(index_path)) if os.path.exists(index_path) else {}
    for scene in args.scenes.split(","):
        if scene not in SCENES:
            raise SystemExit(f"references: unknown scene '{scene}' (one of {', '.join(SCENES)})")
        xml = os.path.join("scenes", scene + ".xml")
        params = param_set(scene, args.params)
        name = f"{scene}-{args.params}-{args.res}"
        key = {"scene_sha256": scene_digest(xml), "params": params, "res": args.res, "seconds": args.seconds,
               "spp": args.spp,
               "study_spp": args.study_spp, "check_spp": args.check_spp, "study": "blocks+pixels+se",
               "max_step_bias": args.max_step_bias}
        old = index.get(name)
        if old and not args.force and old.get("key") == key and os.path.exists(os.path.join(ROOT, old["file"])):
            print(f"references: {name}: cached ({old['file']}, {old['spp']} spp)")
            if args.recheck_quadric:
                quadric_check(qsil, xml, params, args.check_spp, name)
            if args.recheck or args.recheck_quadric:
                ok, stats, _, _ = agree(qsil, os.path.join(OUT, f"{name}-check-quadric.exr"),
                                        os.path.join(OUT, f"{name}-check-fd.exr"))
                old["quadric_check"].update({"agree": ok, "stats": stats})
                write_index(index, index_path)
                print(f"references: {name}: quadric agrees at 64x64: {ok} ({stats})")
            continue
        if args.recheck or args.recheck_quadric:
            raise SystemExit(f"references: {name}: no cached reference with these options to recheck")
        study = step_study(qsil, xml, params, args.res, args.study_spp, name, args.max_step_bias)
        spp = args.spp or max(args.study_spp, int(args.seconds / study["seconds_per_spp"]))
        path = os.path.join(OUT, name + ".exr")
        seconds, floor = reference(qsil, xml, params, args.res, "fd", spp, 7, path, study["steps"])
        qa = quadric_check(qsil, xml, params, args.check_spp, name)
        fa = os.path.join(OUT, f"{name}-check-fd.exr")
        reference(qsil, xml, params, 64, "fd", args.check_spp, 12, fa, study["steps"])
        ok, stats, _, _ = agree(qsil, qa, fa)
        index[name] = {"key": key, "scene": xml, "params": params, "res": args.res, "file": path, "method": "fd",
                       "spp": spp, "steps": study["steps"], "seconds": seconds, "rel_noise_floor": floor,
                       "step_study": study,
                       "quadric_check": {"res": 64, "spp": args.check_spp, "agree": ok, "stats": stats}}
        write_index(index, index_path)
        print(f"references: {name}: {spp} spp, steps {study['steps']}, {seconds:.0f} s, rel. floor {floor:.3g}, "
              f"quadric agrees at 64x64: {ok}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
