"""tools/results_report.py's targets table: the ratio cells judge a target only where the reference can.

Run by ctest with the bindings' suite (tests/CMakeLists.txt, QSIL_SOURCE_DIR=<repository>). The oracle is
the algebra of a common floor: measured MSE = method's own MSE + floor, so the raw ratio is a bound on the
ratio of the methods' own errors, on the side away from 1.
"""
import os
import sys

import pytest

ROOT = os.environ.get("QSIL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))

from results_report import ratio_cell  # noqa: E402


def test_a_floor_within_a_tenth_gives_the_floor_subtracted_ratio():
    assert ratio_cell(0.479, 0.035, 0.00131) == f"{(0.479 - 0.00131) / (0.035 - 0.00131):.3g}"


@pytest.mark.parametrize("own_a,own_b,floor", [(0.8, 0.002, 0.173), (0.3, 0.18, 0.722), (0.01, 0.2, 0.05),
                                               (0.05, 0.05, 0.5)])
def test_a_high_floor_gives_the_raw_ratio_as_a_bound_that_holds(own_a, own_b, floor):
    a, b = own_a + floor, own_b + floor
    cell = ratio_cell(a, b, floor)
    bound = float(cell.split()[1])
    assert cell.startswith("≥" if a >= b else "≤")
    # The bound holds for the methods' own ratio (to the cell's 3 significant digits).
    if a >= b:
        assert own_a / own_b >= bound * (1 - 5e-3)
    else:
        assert own_a / own_b <= bound * (1 + 5e-3)
    assert cell.endswith(f"(est. {own_a / own_b:.3g})")


def test_the_floor_is_judged_against_the_smaller_error():
    # 0.02 is within a tenth of the larger error (0.5) but not of the smaller (0.1): not judged.
    assert ratio_cell(0.5, 0.1, 0.02).startswith("≥")
    assert ratio_cell(0.1, 0.5, 0.02).startswith("≤")
    assert ratio_cell(0.5, 0.1, 0.01) == f"{0.49 / 0.09:.3g}"
