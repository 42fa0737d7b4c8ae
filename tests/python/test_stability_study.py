"""tools/stability_study.py's reference cache: a cached FD reference is reused only when it was made from the
same scene files, parameter, resolution, spp, steps and threads, and a failed render leaves no record.

Run by ctest with the bindings' suite (tests/CMakeLists.txt, QSIL_SOURCE_DIR=<repository>). qsil and git are
replaced by a fake subprocess.run that counts renders and writes the reference file a render would.
"""
import argparse
import os
import subprocess
import sys

ROOT = os.environ.get("QSIL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))

import references  # noqa: E402
import stability_study  # noqa: E402


def test_a_reference_is_reused_only_when_everything_it_was_made_from_matches(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(references, "ROOT", str(tmp_path))
    (tmp_path / "scene.xml").write_text('<scene><string name="filename" value="mesh.obj"/></scene>')
    (tmp_path / "mesh.obj").write_text("v 0 0 0\n")
    renders = []
    fail = {"next": False}

    def fake_run(cmd, **kwargs):
        if cmd[0] == "git":
            return subprocess.CompletedProcess(cmd, 0, "abc1234\n", "")
        renders.append(cmd)
        if fail["next"]:
            fail["next"] = False
            return subprocess.CompletedProcess(cmd, 1, "", "qsil: error")
        open(cmd[cmd.index("-o") + 1], "w").write("exr")
        return subprocess.CompletedProcess(cmd, 0, "", "")

    monkeypatch.setattr(stability_study.subprocess, "run", fake_run)
    args = argparse.Namespace(qsil="qsil", res=48, ref_spp=100, threads=2, force_references=False)

    def make(steps=(0.001,)):
        return stability_study.make_reference(args, "scene.xml", ["-D", "res=48"], "s:translate:0,1,0", list(steps),
                                              "ref.exr")

    assert make() is None and len(renders) == 1
    assert make() is None and len(renders) == 1  # reused
    assert make(steps=(0.0005,)) is None and len(renders) == 2  # another step
    assert make(steps=(0.0005,)) is None and len(renders) == 2
    args.ref_spp = 200
    assert make(steps=(0.0005,)) is None and len(renders) == 3  # more spp
    (tmp_path / "mesh.obj").write_text("v 0 0 1\n")
    assert make(steps=(0.0005,)) is None and len(renders) == 4  # a mesh the scene names changed
    args.force_references = True
    assert make(steps=(0.0005,)) is None and len(renders) == 5
    args.force_references = False
    # A failed render returns its error and leaves no record: the next run renders again.
    args.threads = 1
    fail["next"] = True
    assert make(steps=(0.0005,)) == "reference failed (1)" and len(renders) == 6
    assert not os.path.exists("ref.json")
    assert make(steps=(0.0005,)) is None and len(renders) == 7
    assert make(steps=(0.0005,)) is None and len(renders) == 7


def test_the_record_holds_every_scene_and_method_as_the_table_does(tmp_path):
    # write_record keeps what results_report judges the stability targets from: per scene and method
    # the relative MSE, z and the reference's floor, or the method's error; nothing else of the row.
    args = argparse.Namespace(budget=2.0, repeats=3, res=48, ref_spp=100, ref_step_factor=0.25, threads=2)
    row = {"rel_mse": 0.13, "rel_mse_runs": [0.1, 0.12, 0.17], "z": -0.9, "spp": 358, "wall_seconds": 2.0,
           "nonfinite_pixels": 0, "zero_contribution_rate": 0.32, "rel_noise_floor": 0.002, "sum": [1.0], "mse": 3.0}
    per = {m: dict(row) for m in stability_study.METHODS}
    per["vsphere"] = {"error": "exit -11 (crash)"}
    table = [("teapot", "teapot:translate:0,1,0", "a question", per)]
    record = stability_study.write_record(args, table, str(tmp_path), "abc1234", "2026-11-25")
    import json
    assert json.load(open(tmp_path / "results.json")) == record
    assert not os.path.exists(tmp_path / "results.json.tmp")
    scene = record["scenes"][0]
    assert scene["name"] == "teapot" and scene["param"] == "teapot:translate:0,1,0"
    assert scene["methods"]["vsphere"] == {"error": "exit -11 (crash)"}
    # Named, not taken from RECORD_FIELDS: what results_report's stability targets read, and the table's cells.
    assert scene["methods"]["quadric"] == {f: row[f] for f in ("rel_mse", "rel_mse_runs", "z", "spp", "wall_seconds",
                                                                 "nonfinite_pixels", "zero_contribution_rate",
                                                                 "rel_noise_floor")}
    assert record["commit"] == "abc1234" and record["ref_spp"] == 100 and record["repeats"] == 3


def test_runs_pool_into_the_mean_error_and_the_z_of_the_mean_sum():
    # pool_runs: the mean relative MSE (not one run's, nor the median, which would hide a tail), a
    # z whose standard error divides the runs' variance by their count but not the reference's
    # (common to all runs), summed non-finite pixels.
    runs = [{"rel_mse": r, "spp": spp, "wall_seconds": 2.0, "nonfinite_pixels": nf, "zero_contribution_rate": 0.3,
             "sum_error": [e], "sum_se": [se]}
            for r, spp, nf, e, se in ((0.1, 100, 0, 1.0, 2.0), (0.1, 110, 1, 2.0, 2.0), (1.0, 120, 0, 3.0, 2.0))]
    row = stability_study.pool_runs(runs, ref_se=1.0)
    assert abs(row["rel_mse"] - 0.4) < 1e-12 and row["rel_mse_runs"] == [0.1, 0.1, 1.0]
    assert row["spp"] == 110 and row["nonfinite_pixels"] == 1
    # mean error 2, se = sqrt(4 / 3 + 1)
    assert abs(row["z"] - 2.0 / (4.0 / 3.0 + 1.0) ** 0.5) < 1e-12
    assert abs(row["zero_contribution_rate"] - 0.3) < 1e-12
    one = stability_study.pool_runs(runs[:1], ref_se=1.0)
    assert one["rel_mse"] == 0.1 and abs(one["z"] - 1.0 / 5.0 ** 0.5) < 1e-12
    cell = stability_study.cell({**row, "z": 0.5})
    assert "0.4 (0.1–1)" in cell and "(110 spp)" in cell
