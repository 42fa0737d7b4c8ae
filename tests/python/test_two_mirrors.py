"""examples/two_mirrors.py's geometry for the "seen part" score: the segment test and the test of
what the camera sees by one reflection, against hand-computed cases (a mirror facing the camera,
a point straight behind it, one seen off-axis, one whose reflection misses the mirror, one
hidden by an occluder).

Run by ctest with the bindings' suite (QSIL_SOURCE_DIR=<repository>); NumPy only.
"""
import importlib.util
import os

import numpy as np

ROOT = os.environ.get("QSIL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
spec = importlib.util.spec_from_file_location("two_mirrors", os.path.join(ROOT, "examples", "two_mirrors.py"))
two_mirrors = importlib.util.module_from_spec(spec)
spec.loader.exec_module(two_mirrors)

# One triangle in the plane z = 0 around the z axis.
TRI_V = np.array([[-0.2, -0.2, 0.0], [0.2, -0.2, 0.0], [0.0, 0.3, 0.0]])
TRI_F = np.array([[0, 1, 2]])


def test_occluded_segments():
    o = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]])
    t = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 0.5], [0.0, 0.0, 1e-9], [1.0, 0.0, -1.0]])
    # Through the triangle; ending before it; ending on it (the ends excluded); beside it.
    assert list(two_mirrors.occluded(o, t, TRI_V, TRI_F)) == [True, False, False, False]


class MirrorScene:
    """A stand-in for qsil.Scene: a 2 x 2 mirror at z = -2 facing the camera at the origin, and
    the other mirror far out of view."""

    def vertices(self, name):
        if name == "mirror-left":
            return np.array([[-1.0, -1.0, -2.0], [1.0, -1.0, -2.0], [1.0, 1.0, -2.0], [-1.0, 1.0, -2.0]])
        return np.array([[50.0, -1.0, -2.0], [52.0, -1.0, -2.0], [52.0, 1.0, -2.0], [50.0, 1.0, -2.0]])


def test_seen_in_a_mirror():
    # The camera's image in the mirror is (0, 0, -4). Points behind the camera (z = 1):
    # - (0.9, 0, 1): meets the mirror at (0.36, 0, -2), inside it and in view; the occluder
    #   (at z = 0, |x| <= 0.2) is beside its path: seen.
    # - (0, 0, 1): straight on, through the occluder: not seen.
    # - (3, 0, 1): meets the mirror's plane at x = 1.2, outside it: not seen.
    # - (0, 0.9, 1) with a half field of view of 5 degrees: its mirror point (0, 0.36, -2) is out
    #   of view (0.36 / 2 > tan 5 deg), seen with 25 degrees.
    points = np.array([[0.9, 0.0, 1.0], [0.0, 0.0, 1.0], [3.0, 0.0, 1.0], [0.0, 0.9, 1.0]])
    wide = two_mirrors.seen_in_mirrors(points, TRI_V, TRI_F, MirrorScene(), np.radians(25.0))
    assert list(wide) == [True, False, False, True]
    narrow = two_mirrors.seen_in_mirrors(points, TRI_V, TRI_F, MirrorScene(), np.radians(5.0))
    assert list(narrow) == [False, False, False, False]
