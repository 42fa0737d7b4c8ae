"""examples/two_mirrors.py's geometry for the "seen part" score: the segment test, the camera's frame
and view, and the test of what the camera sees directly and by one reflection, against
hand-computed cases (a mirror facing the camera, a point straight behind it, one seen off-axis,
one whose reflection misses the mirror, one hidden by an occluder on the way to the mirror or
back from it); and the page's set-up line for one spp and for one spp per phase.

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


# A camera at the origin, looking along -z.
AXIS_CAMERA = two_mirrors.camera_frame('<lookat origin="0, 0, 0" target="0, 0, -1" up="0, 1, 0"/>')


def test_camera_frame_and_view():
    o, f, r, u = two_mirrors.camera_frame('<lookat origin="0, 0.9, 0" target="0, 0, -3.4" up="0, 1, 0"/>')
    assert np.allclose(o, [0, 0.9, 0])
    assert np.allclose(f, np.array([0, -0.9, -3.4]) / np.hypot(0.9, 3.4))
    assert np.allclose(r, [1, 0, 0])  # right of a camera looking along -z with y up is +x
    assert np.allclose(u, np.cross(r, f)) and u[1] > 0
    # The target is in view; a point behind the camera is not; one 30 deg off the axis is in view
    # with a half field of view of 35 deg, not with 25.
    q = np.array([[0.0, 0.0, -3.4], [0.0, 0.9, 1.0], [np.tan(np.radians(30)), 0.0, -1.0]])
    assert list(two_mirrors.in_view(q, AXIS_CAMERA, np.radians(35))) == [True, False, True]
    assert list(two_mirrors.in_view(q, AXIS_CAMERA, np.radians(25))) == [True, False, False]
    # The tilted camera (looking 14.8 deg down): its target is in view; (0, 0.9, -1), straight ahead
    # level with it, is 14.8 deg above its axis: in view with a half field of view of 25 deg, not 10.
    tilted = (o, f, r, u)
    q = np.array([[0.0, 0.0, -3.4], [0.0, 0.9, -1.0]])
    assert list(two_mirrors.in_view(q, tilted, np.radians(25))) == [True, True]
    assert list(two_mirrors.in_view(q, tilted, np.radians(10))) == [True, False]


def test_camera_frame_refuses_a_degenerate_lookat():
    for bad in ('<lookat origin="0, 0, 0" target="0, 1, 0" up="0, 1, 0"/>', '<lookat origin="0, 0, 0" up="0, 1, 0"/>'):
        try:
            two_mirrors.camera_frame(bad)
        except ValueError:
            continue
        raise AssertionError("no error for %s" % bad)


def test_seen_in_a_mirror():
    # The camera's image in the mirror is (0, 0, -4). Points behind the camera (z = 1), out of its
    # direct view, and the occluder (the triangle moved to z = 0.5, |x| <= 0.2):
    # - (0.9, 0, 1): meets the mirror at (0.36, 0, -2), inside it and in view; the occluder is
    #   beside its path (x = 0.85 at z = 0.5): seen.
    # - (0, 0, 1): straight on, through the occluder: not seen.
    # - (3, 0, 1): meets the mirror's plane at x = 1.2, outside it: not seen.
    # - (0, 0.9, 1) with a half field of view of 5 degrees: its mirror point (0, 0.36, -2) is out
    #   of view (0.36 / 2 > tan 5 deg), seen with 25 degrees (it passes the occluder at y = 0.81).
    V = TRI_V + np.array([0.0, 0.0, 0.5])
    points = np.array([[0.9, 0.0, 1.0], [0.0, 0.0, 1.0], [3.0, 0.0, 1.0], [0.0, 0.9, 1.0]])
    direct, wide = two_mirrors.seen_by_camera(points, V, TRI_F, MirrorScene(), AXIS_CAMERA, np.radians(25.0))
    assert list(wide) == [True, False, False, True]
    assert not direct.any()
    direct, narrow = two_mirrors.seen_by_camera(points, V, TRI_F, MirrorScene(), AXIS_CAMERA, np.radians(5.0))
    assert list(narrow) == [False, False, False, False]


def test_seen_directly_and_the_way_back_from_the_mirror():
    # Points in front of the camera (z < 0), between it and the mirror at z = -2:
    # - (0.3, 0, -1): in view, nothing between it and the camera: seen directly; its reflection
    #   (the segment to (0, 0, -4)) meets the mirror at (0.2, 0, -2), but the way from there to the
    #   camera crosses the occluder (the triangle moved to z = -0.5) at x = 0.05: not seen in the mirror.
    # - (0, 0, -1): behind the occluder at z = -0.5 as seen from the camera: not seen directly.
    # - (0.3, 0, -1) with a half field of view of 5 deg: out of view (0.3 > tan 5 deg).
    V = TRI_V + np.array([0.0, 0.0, -0.5])
    points = np.array([[0.3, 0.0, -1.0], [0.0, 0.0, -1.0]])
    direct, mirrored = two_mirrors.seen_by_camera(points, V, TRI_F, MirrorScene(), AXIS_CAMERA, np.radians(25.0))
    assert list(direct) == [True, False]
    assert list(mirrored) == [False, False]
    direct, _ = two_mirrors.seen_by_camera(points[:1], V, TRI_F, MirrorScene(), AXIS_CAMERA, np.radians(5.0))
    assert list(direct) == [False]


def test_page_names_a_per_phase_spp():
    # --spp 4,4,1,1 records a list; the page's set-up names it per phase, as the film sizes.
    import json
    with open(os.path.join(ROOT, "docs", "images", "two-mirrors", "results.json")) as f:
        record = json.load(f)
    record["spp"] = 4
    assert "; 4 spp per step" in two_mirrors.page_text(record)
    record["spp"] = [4, 4, 1, 1]
    record["res"] = [64, 128, 256, 256]
    assert "; 4 → 4 → 1 → 1 spp per step" in two_mirrors.page_text(record)


def test_per_phase_lists():
    assert two_mirrors.per_phase("64,128,256", 4) == [64, 128, 256, 256]
    assert two_mirrors.per_phase("4", 3) == [4, 4, 4]
    for bad in ("64,x", "0,4", "1,2,3,4,5"):
        try:
            two_mirrors.per_phase(bad, 4)
        except ValueError:
            continue
        raise AssertionError("accepted %r" % bad)
