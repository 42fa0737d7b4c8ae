"""tools/boundary_variance.py's leave-one-seed-out range: it brackets the full variance sum, equals the
variance of the remaining seeds computed directly, and exposes a sum that one seed carries.

Run by ctest with the bindings' suite (tests/CMakeLists.txt, QSIL_SOURCE_DIR=<repository>).
"""
import os
import sys

import numpy as np
import pytest

ROOT = os.environ.get("QSIL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))

import boundary_variance  # noqa: E402


def test_each_left_out_sum_is_the_variance_of_the_other_seeds():
    rng = np.random.default_rng(7)
    runs = rng.normal(size=(6, 4, 5)) * np.arange(1, 21).reshape(4, 5)
    direct = [np.delete(runs, i, axis=0).var(axis=0, ddof=1).sum() for i in range(6)]
    lo, hi = boundary_variance.leave_one_out_range(runs)
    assert lo == pytest.approx(min(direct), rel=1e-12)
    assert hi == pytest.approx(max(direct), rel=1e-12)
    full = runs.var(axis=0, ddof=1).sum()
    assert lo <= full <= hi


def test_one_seeds_outlier_spans_the_range_and_gaussian_runs_do_not():
    rng = np.random.default_rng(11)
    runs = rng.normal(size=(64, 8, 8))
    lo, hi = boundary_variance.leave_one_out_range(runs)
    assert hi / lo < 1.1  # 64 seeds of a light-tailed estimator: each left out moves the sum by ~1/64
    runs[17, 3, 3] = 400.0  # one rare sample, worth 400 standard deviations
    lo, hi = boundary_variance.leave_one_out_range(runs)
    assert hi / lo > 10


def test_fewer_than_three_seeds_are_refused():
    with pytest.raises(ValueError, match="at least 3 seeds"):
        boundary_variance.leave_one_out_range(np.zeros((2, 3, 3)))
