"""The Python module `qsil` (python/qsil_module.cpp) as an optimisation loop uses it.

Run by ctest (tests/CMakeLists.txt: PYTHONPATH=<build>/python, QSIL_SOURCE_DIR=<repository>).
The oracle for gradients is forward mode on the same paths: with the interior term alone both
modes trace the same paths for a seed, so sum_v dL/dx_v . dx_v/dtheta equals sum_x w(x) dI/dtheta
to rounding (the C++ suite, tests/integrators/reverse_test.cpp, checks the boundary terms
statistically and against finite differences).
"""
import os

import numpy as np
import pytest

import qsil

ROOT = os.environ.get("QSIL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
SELFSHADOW = os.path.join(ROOT, "tests", "data", "gradient", "spot-selfshadow.xml")
MIRROR = os.path.join(ROOT, "scenes", "spot-mirror.xml")


def load(path=SELFSHADOW, res=16, spp=4, **defines):
    d = {"res": str(res), "spp": str(spp)}
    d.update({k: str(v) for k, v in defines.items()})
    return qsil.Scene(path, d)


def test_scene_exposes_its_geometry():
    s = load()
    assert (s.width, s.height, s.spp) == (16, 16, 4)
    assert s.shape_ids == ["spot", "light"]
    v, t = s.vertices("spot"), s.triangles("spot")
    assert v.shape[1] == 3 and v.dtype == np.float64 and len(v) > 1000
    assert t.shape[1] == 3 and t.min() == 0 and t.max() == len(v) - 1


def test_render_is_deterministic_for_any_thread_count():
    s = load()
    a = qsil.render(s, spp=2, seed=7, threads=1)
    b = qsil.render(s, spp=2, seed=7, threads=2)
    assert a.shape == (16, 16, 3) and np.isfinite(a).all() and a.sum() > 0
    assert np.array_equal(a, b)
    assert not np.array_equal(a, qsil.render(s, spp=2, seed=8))


def test_set_vertices_round_trip_and_motion():
    s = load()
    before = qsil.render(s, spp=2, seed=1)
    v = s.vertices("spot")
    s.set_vertices("spot", v)
    assert np.array_equal(qsil.render(s, spp=2, seed=1), before)
    s.set_vertices("spot", v + np.array([0.3, 0.0, 0.0]))
    assert np.abs(qsil.render(s, spp=2, seed=1) - before).sum() > 1.0
    assert np.allclose(s.vertices("spot"), v + np.array([0.3, 0.0, 0.0]))


def test_reverse_equals_forward_mode_on_the_same_paths():
    # Spot above a GGX mirror, 5 segments (paths with several hits on Spot and the mirror).
    s = load(MIRROR, res=16, spp=2, max_depth=5)
    rng = np.random.default_rng(3)
    w = rng.uniform(-1, 1, size=(s.height, s.width, 3))
    params = ["spot:translate:0.3,1,-0.2", "spot:rotate:0,1,0"]
    image, d = qsil.grad(s, params, seed=5, boundary="none")
    r = qsil.reverse(s, ["spot", "mirror"], w, seed=5, boundary="none")
    assert np.allclose(r["image"], image, rtol=1e-12, atol=1e-12)
    assert r["loss"] == pytest.approx(float((w * image).sum()), rel=1e-9)
    g = r["gradient"]["spot"]
    x = s.vertices("spot")
    centre = 0.5 * (x.min(axis=0) + x.max(axis=0))
    velocities = [np.broadcast_to([0.3, 1.0, -0.2], x.shape), np.cross([0.0, 1.0, 0.0], x - centre)]
    for k, vel in enumerate(velocities):
        forward = float((w * d[k]).sum())
        backward = float((g * vel).sum())
        assert abs(forward) > 1e-3, "vacuous"
        assert backward == pytest.approx(forward, rel=1e-9), params[k]
    assert r["gradient"]["mirror"].shape == (s.vertices("mirror").shape[0], 3)


def test_reverse_with_the_boundary_term_is_finite_and_deterministic():
    s = load()
    w = np.ones((16, 16, 3))
    a = qsil.reverse(s, ["spot"], w, spp=2, seed=3, threads=1)
    b = qsil.reverse(s, ["spot"], w, spp=2, seed=3, threads=2)
    assert np.isfinite(a["gradient"]["spot"]).all() and a["nonfinite"] == 0
    assert np.array_equal(a["gradient"]["spot"], b["gradient"]["spot"])
    assert np.count_nonzero(np.abs(a["gradient"]["spot"]).sum(axis=1)) > 100


def test_old_keyword_names_set_the_same_rates():
    # sppi / sppp, as Mitsuba 3 names them; boundary_spp / primary_samples, the names before them,
    # still set the same values: equal images, and unequal to the defaults'.
    s = load()
    _, new = qsil.grad(s, ["spot:translate:0,1,0"], spp=2, seed=4, sppi=2, sppp=0.5)
    _, old = qsil.grad(s, ["spot:translate:0,1,0"], spp=2, seed=4, boundary_spp=2, primary_samples=0.5)
    _, default = qsil.grad(s, ["spot:translate:0,1,0"], spp=2, seed=4)
    assert np.array_equal(new, old) and not np.array_equal(new, default)
    w = np.ones((16, 16, 3))
    a = qsil.reverse(s, ["spot"], w, spp=2, seed=3, sppi=2)
    b = qsil.reverse(s, ["spot"], w, spp=2, seed=3, boundary_spp=2)
    assert np.array_equal(a["gradient"]["spot"], b["gradient"]["spot"])


def test_bad_input_raises_qsil_error_with_one_line():
    s = load(res=8, spp=1)
    cases = [
        (lambda: qsil.reverse(s, ["cow"], np.zeros((8, 8, 3))), "--shape 'cow': no shape with this id"),
        (lambda: qsil.reverse(s, ["spot"], np.zeros((8, 9, 3))), "expected an array of shape (8, 8, 3)"),
        (lambda: qsil.reverse(s, ["spot"], np.full((8, 8, 3), np.nan)), "non-finite weight at pixel (0, 0)"),
        (lambda: qsil.reverse(s, ["spot"], np.zeros((8, 8, 3)), boundary="fd"), "boundary"),
        (lambda: qsil.grad(s, ["spot:wobble:1"]), "unknown kind"),
        (lambda: s.set_vertices("spot", np.zeros((3, 3))), "expected an array of shape"),
        (lambda: s.vertices("cow"), "shape 'cow': no shape with this id"),
        (lambda: qsil.Scene(os.path.join(ROOT, "no-such.xml")), "no-such.xml"),
    ]
    for call, needle in cases:
        with pytest.raises(qsil.Error) as e:
            call()
        assert isinstance(e.value, ValueError)
        assert needle in str(e.value) and "\n" not in str(e.value), str(e.value)
