"""tools/fd_gap.py's targets: SCENE.xml:ID:translate:X,Y,Z, the direction as qsil moves the shape
(theta (X, Y, Z), not normalised); other kinds are refused
with the text that was given (FD there moves every vertex of the shape by +-h along the direction).

Run by ctest with the bindings' suite (tests/CMakeLists.txt, QSIL_SOURCE_DIR=<repository>).
"""
import os
import sys

import numpy as np
import pytest

ROOT = os.environ.get("QSIL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))

import fd_gap  # noqa: E402


def test_a_translation_gives_the_scene_the_parameter_the_shape_and_its_direction_as_given():
    scene, param, shape, d = fd_gap.parse_target("scenes/stability/sun.xml:spot:translate:0,2,0")
    assert scene == "scenes/stability/sun.xml"
    assert param == "spot:translate:0,2,0"
    assert shape == "spot"
    np.testing.assert_allclose(d, [0.0, 2.0, 0.0])  # qsil's --param moves by theta (0, 2, 0)


@pytest.mark.parametrize("text", [
    "scenes/stability/open-box.xml:box:rotate:0,1,0",  # not a translation
    "scenes/stability/sun.xml:spot:translate:0,0,0",   # no direction
    "scenes/stability/sun.xml:spot:translate:1,2",     # two numbers
    "scenes/stability/sun.xml:spot:translate:1,nan,0",
    "spot:translate:1,0,0",                            # no scene
])
def test_anything_else_is_refused_with_its_text(text):
    with pytest.raises(ValueError, match=text.split(":")[0]):
        fd_gap.parse_target(text)
