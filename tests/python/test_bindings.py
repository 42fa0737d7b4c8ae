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
import qsil_shape

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


def icosphere(subdivisions=2, radius=0.5, centre=(0.0, 0.3, 0.0)):
    """qsil_shape.icosphere with this file's defaults (a sphere where Spot stands)."""
    return qsil_shape.icosphere(subdivisions, centre, radius)


def test_set_mesh_replaces_vertices_and_triangles():
    s = load()
    before = qsil.render(s, spp=2, seed=1)
    v, t = s.vertices("spot"), s.triangles("spot")
    s.set_mesh("spot", v, t)
    assert np.array_equal(qsil.render(s, spp=2, seed=1), before), "the same mesh renders the same image"
    sv, st = icosphere()
    s.set_mesh("spot", sv, st)
    assert np.array_equal(s.vertices("spot"), sv) and np.array_equal(s.triangles("spot"), st)
    assert np.abs(qsil.render(s, spp=2, seed=1) - before).sum() > 1.0
    # The edge structure follows the new mesh: forward and reverse mode run on it, and reverse mode's
    # gradient has one row per new vertex.
    _, d = qsil.grad(s, ["spot:translate:1,0,0"], spp=2, seed=1)
    assert np.isfinite(d).all() and np.abs(d).sum() > 0
    g = qsil.reverse(s, ["spot"], np.ones((s.height, s.width, 3)), spp=2, seed=1)["gradient"]["spot"]
    assert g.shape == sv.shape and np.isfinite(g).all() and np.abs(g).sum() > 0


def test_set_mesh_rejects_bad_input_and_keeps_the_mesh():
    s = load(res=8, spp=1)
    v, t = s.vertices("spot"), s.triangles("spot")
    bad = [
        (lambda: s.set_mesh("spot", v[:, :2], t), "expected positions of shape (V, 3)"),
        (lambda: s.set_mesh("spot", v, t[:, :2]), "expected triangles of shape (T, 3)"),
        (lambda: s.set_mesh("spot", v, t + len(v)), "refers to vertex"),
        (lambda: s.set_mesh("spot", v, np.array([[0, 0, 1]])), "triangle 0 has zero area"),
        (lambda: s.set_mesh("spot", np.full_like(v, np.nan), t), "vertex 0 is non-finite"),
        (lambda: s.set_mesh("cow", v, t), "shape 'cow': no shape with this id"),
    ]
    for call, needle in bad:
        with pytest.raises(qsil.Error) as e:
            call()
        assert needle in str(e.value) and "\n" not in str(e.value), str(e.value)
    assert np.array_equal(s.vertices("spot"), v) and np.array_equal(s.triangles("spot"), t)


def test_set_resolution_changes_the_film_and_back():
    s = load(res=16, spp=1)
    before = qsil.render(s, spp=1, seed=4)
    s.set_resolution(24, 12)
    assert (s.width, s.height) == (24, 12)
    assert qsil.render(s, spp=1, seed=4).shape == (12, 24, 3)
    assert qsil.grad(s, ["spot:translate:1,0,0"], spp=1)[1].shape == (1, 12, 24, 3)
    s.set_resolution(16, 16)
    assert np.array_equal(qsil.render(s, spp=1, seed=4), before)
    for w, h in ((0, 16), (16, -1), (1 << 17, 16)):
        with pytest.raises(qsil.Error) as e:
            s.set_resolution(w, h)
        assert "must be in [1, 65536]" in str(e.value)
    assert (s.width, s.height) == (16, 16)


def test_intersection_curves_switch_reaches_both_modes():
    # A sphere sunk into a floor: the curve where they cross is sampled unless switched off, so the
    # derivative changes; where nothing crosses (Spot under a light), the switch changes nothing.
    sunk = qsil.Scene(os.path.join(ROOT, "tests", "data", "gradient", "sunk-sphere.xml"), {"res": "16", "spp": "4"})
    on = qsil.grad(sunk, ["sphere:translate:0,1,0"], spp=4, seed=3)[1]
    off = qsil.grad(sunk, ["sphere:translate:0,1,0"], spp=4, seed=3, intersection_curves=False)[1]
    assert not np.array_equal(on, off)
    w = np.ones((16, 16, 3))
    g_on = qsil.reverse(sunk, ["sphere"], w, spp=4, seed=3)["gradient"]["sphere"]
    g_off = qsil.reverse(sunk, ["sphere"], w, spp=4, seed=3, intersection_curves=False)["gradient"]["sphere"]
    assert not np.array_equal(g_on, g_off)
    s = load(res=8, spp=2)
    a = qsil.grad(s, ["spot:translate:1,0,0"], spp=2, seed=3)[1]
    assert np.array_equal(a, qsil.grad(s, ["spot:translate:1,0,0"], spp=2, seed=3, intersection_curves=False)[1])


def test_camera_control_switch_reaches_the_estimator():
    # Attached camera hits on the sunk sphere: the control variate (camera_control_spp, default 4)
    # changes the derivative, not the image (the same paths); 0 turns it off; 1 is refused.
    sunk = qsil.Scene(os.path.join(ROOT, "tests", "data", "gradient", "sunk-sphere.xml"), {"res": "16", "spp": "4"})
    run = lambda **k: qsil.grad(sunk, ["sphere:translate:0,1,0"], spp=4, seed=3, camera_hits="attached", **k)
    image, on = run()
    image_off, off = run(camera_control_spp=0)
    assert np.array_equal(image, image_off)
    assert not np.array_equal(on, off)
    assert np.array_equal(on, run(camera_control_spp=4)[1])
    with pytest.raises(qsil.Error) as e:
        run(camera_control_spp=1)
    assert "at least 2 pre-pass spp (got 1)" in str(e.value)


def test_reverse_takes_the_camera_hits_and_keeps_the_control_across_an_update():
    # Reverse mode's camera_hits and camera_control_spp reach the estimator (each changes the
    # gradient of the same paths; 1 is refused), and an update() keeps the set-up's control
    # variate: after an update of unmoved vertices the gradient is the set-up's, bit for bit; after
    # a change of film size, a new estimator's.
    sunk = qsil.Scene(os.path.join(ROOT, "tests", "data", "gradient", "sunk-sphere.xml"), {"res": "16", "spp": "4"})
    adjoint = np.where(np.random.default_rng(5).random((16, 16, 3)) < 0.5, -1.0, 1.0)
    run = lambda **k: qsil.reverse(sunk, ["sphere"], adjoint, spp=4, seed=3, threads=2, **k)["gradient"]["sphere"]
    on = run(camera_hits="attached")
    assert not np.array_equal(on, run(camera_hits="attached", camera_control_spp=0))
    assert not np.array_equal(on, run(camera_hits="detached"))
    with pytest.raises(qsil.Error) as e:
        run(camera_hits="attached", camera_control_spp=1)
    assert "at least 2 pre-pass spp (got 1)" in str(e.value)
    estimator = qsil.ReverseEstimator(sunk, ["sphere"], camera_hits="attached")
    assert np.array_equal(estimator.run(adjoint, spp=4, seed=3, threads=2)["gradient"]["sphere"], on)
    assert estimator.update()["refitted"]
    assert np.array_equal(estimator.run(adjoint, spp=4, seed=3, threads=2)["gradient"]["sphere"], on)
    # Another film size: the old c does not fit, so the update runs the pre-pass anew, as a new
    # estimator's set-up does (without it: c = 0, another gradient).
    sunk.set_resolution(24, 24)
    adjoint24 = np.where(np.random.default_rng(6).random((24, 24, 3)) < 0.5, -1.0, 1.0)
    estimator.update()
    assert np.array_equal(estimator.run(adjoint24, spp=4, seed=3, threads=2)["gradient"]["sphere"],
                          qsil.reverse(sunk, ["sphere"], adjoint24, spp=4, seed=3, threads=2,
                                       camera_hits="attached")["gradient"]["sphere"])


def mesh_edges(F):
    """Directed edges (T*3, 2) of triangles F."""
    return np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])


def signed_volume(V, F):
    return np.einsum("ij,ij->i", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])).sum() / 6.0


def test_remesh_reaches_the_target_length_and_keeps_a_closed_outward_mesh():
    v, f = icosphere(2, radius=1.0, centre=(0.0, 0.0, 0.0))
    d = mesh_edges(f)
    target = 0.5 * np.linalg.norm(v[d[:, 0]] - v[d[:, 1]], axis=1).mean()
    V, F = qsil.remesh(v, f, target)
    E = mesh_edges(F)
    lengths = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    assert abs(lengths.mean() / target - 1) < 0.15, lengths.mean() / target
    assert len(F) > 2 * len(f), "a finer mesh"
    # Closed, manifold and consistently oriented: each directed edge once, and its reverse once.
    directed = {tuple(e) for e in E}
    assert len(directed) == len(E) and all((b, a) in directed for a, b in directed)
    assert len(V) - len(E) // 2 + len(F) == 2, "a sphere's Euler characteristic"
    # Outward, and on the input surface (within the icosphere's own distance from the unit sphere).
    assert abs(signed_volume(V, F) / signed_volume(v, f) - 1) < 0.02
    assert np.abs(np.linalg.norm(V, axis=1) - 1).max() < 0.05


def test_remesh_output_renders_and_bad_input_raises():
    v, f = icosphere(2, radius=0.5, centre=(0.0, 0.3, 0.0))
    V, F = qsil.remesh(v, f, 0.1, iterations=2)
    s = load(res=8, spp=1)
    s.set_mesh("spot", V, F)
    assert np.isfinite(qsil.render(s, spp=1)).all()
    bad = [(lambda: qsil.remesh(v, f, 0.0), "not a positive finite number"),
           (lambda: qsil.remesh(v, f, np.nan), "not a positive finite number"),
           (lambda: qsil.remesh(v, f, 0.1, iterations=0), "iterations 0 < 1"),
           (lambda: qsil.remesh(v, f + len(v), 0.1), "refers to vertex"),
           (lambda: qsil.remesh(v, np.concatenate([f, f[:1]]), 0.1), "not a manifold"),
           (lambda: qsil.remesh(v[:, :2], f, 0.1), "expected positions (V, 3)")]
    for call, needle in bad:
        with pytest.raises(qsil.Error) as e:
            call()
        assert needle in str(e.value) and "\n" not in str(e.value), str(e.value)


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


def test_reverse_estimator_equals_reverse_and_follows_the_scene():
    s = load(res=12, spp=2)
    adj = np.random.default_rng(3).uniform(-1, 1, (s.height, s.width, 3))
    est = qsil.ReverseEstimator(s, ["spot"])
    a, b = est.run(adj, spp=2, seed=5), qsil.reverse(s, ["spot"], adj, spp=2, seed=5)
    assert np.array_equal(a["image"], b["image"])
    assert np.array_equal(a["gradient"]["spot"], b["gradient"]["spot"])
    # Moved vertices: refitted, the image that of a new set-up (the paths do not depend on the
    # edge structure); without update() run refuses the stale set-up.
    v = s.vertices("spot")
    s.set_vertices("spot", v + 0.01 * np.sin(5 * v[:, [1]]))
    with pytest.raises(qsil.Error, match="call update"):
        est.run(adj, spp=1)
    u = est.update()
    assert u["refitted"] and u["reason"] == "" and u["edge_seconds"] <= u["seconds"], u
    a, b = est.run(adj, spp=2, seed=5), qsil.reverse(s, ["spot"], adj, spp=2, seed=5)
    assert np.array_equal(a["image"], b["image"])
    assert np.isfinite(a["gradient"]["spot"]).all()
    # A new mesh (other counts): set up anew, the same result as qsil.reverse bit for bit.
    sv, st = icosphere()
    s.set_mesh("spot", sv, st)
    u = est.update()
    assert not u["refitted"] and "counts changed" in u["reason"], u
    a, b = est.run(adj, spp=2, seed=5), qsil.reverse(s, ["spot"], adj, spp=2, seed=5)
    assert a["gradient"]["spot"].shape == sv.shape
    assert np.array_equal(a["gradient"]["spot"], b["gradient"]["spot"])
    # A new film size needs an update too (the primary edges).
    s.set_resolution(8, 8)
    with pytest.raises(qsil.Error, match="film size"):
        est.run(np.ones((8, 8, 3)), spp=1)
    est.update()
    assert est.run(np.ones((8, 8, 3)), spp=1)["image"].shape == (8, 8, 3)


def test_reverse_estimator_probe_paths_switch():
    # probe_paths=False traces every path with dual numbers: the same estimate to rounding (the C++
    # test ReverseMode.ProbePassChangesNothingButTheCost checks the counters too), no samples probed.
    s = load(res=12, spp=2)
    adj = np.random.default_rng(4).uniform(-1, 1, (s.height, s.width, 3))
    a = qsil.ReverseEstimator(s, ["spot"]).run(adj, spp=2, seed=6)
    b = qsil.ReverseEstimator(s, ["spot"], probe_paths=False).run(adj, spp=2, seed=6)
    assert 0 < a["probed"] < 12 * 12 * 2 and b["probed"] == 0, (a["probed"], b["probed"])
    np.testing.assert_allclose(a["gradient"]["spot"], b["gradient"]["spot"], rtol=1e-12, atol=0)
    np.testing.assert_allclose(a["image"], b["image"], rtol=1e-12, atol=0)


def test_reverse_estimator_render_is_qsil_render():
    # The primal image from the estimator's own set-up equals qsil.render's bit for bit, as set up
    # and after a step; a stale set-up is refused as run() refuses it.
    s = load(res=12, spp=2)
    est = qsil.ReverseEstimator(s, ["spot"])
    first = est.render(spp=2, seed=9)
    assert np.array_equal(first, qsil.render(s, spp=2, seed=9))
    v = s.vertices("spot")
    s.set_vertices("spot", v + 0.02 * np.sin(5 * v[:, [1]]))
    with pytest.raises(qsil.Error, match="call update"):
        est.render(spp=1)
    est.update()
    moved = est.render(spp=2, seed=9)
    assert np.array_equal(moved, qsil.render(s, spp=2, seed=9))
    assert moved.shape == (12, 12, 3) and moved.sum() > 0
    assert not np.array_equal(moved, first)  # the step changed the image: a comparison with power


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


def test_grad_warns_where_one_pixel_holds_most_of_an_image_sums_variance():
    """qsil.grad warns as `qsil grad` does (the CLI test checks the threshold against the printed
    share): on shadow-quad's 4 x 4 film at seed 1 one pixel holds 74 % of the variance, on its
    32 x 32 film at 8 spp no pixel more than 27 %."""
    import warnings
    shadow = os.path.join(ROOT, "scenes", "shadow-quad.xml")
    for res, spp, expected in ((4, 4, True), (32, 8, False)):
        s = load(shadow, res=res, spp=spp)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            _, d = qsil.grad(s, ["object:translate:0,1,0"], spp=spp, seed=1)
        assert np.isfinite(d).all()
        mine = [w for w in caught if issubclass(w.category, RuntimeWarning) and "qsil.grad: dtheta0: pixel (" in
                str(w.message)]
        assert (len(mine) == 1) == expected, (res, [str(w.message) for w in caught])


def test_regularized_render_and_grad_reach_the_blur_width():
    s = load(os.path.join(ROOT, "tests", "data", "gradient", "penumbra-sign.xml"), res=8, spp=1)
    hard = qsil.render(s, spp=16, seed=3)
    wide = qsil.render(s, spp=16, seed=3, reg_width=3e-2)
    narrow = qsil.render(s, spp=16, seed=3, reg_width=1e-4)
    assert np.isfinite(wide).all() and wide.shape == hard.shape
    # A wide blur changes the image more than a narrow one does.
    assert np.abs(wide - hard).sum() > 2 * np.abs(narrow - hard).sum()
    img, d = qsil.grad(s, ["occluder:translate:0,1,0"], spp=16, seed=3, boundary="regularized", reg_width=3e-2)
    assert img.shape == (8, 8, 3) and np.isfinite(img).all()
    assert d.shape == (1, 8, 8, 3) and np.isfinite(d).all() and np.abs(d).sum() > 0
    with pytest.raises(qsil.Error) as e:
        qsil.render(s, reg_width=-1.0)
    assert "width must be positive" in str(e.value)


def test_projective_grad_reaches_its_guide():
    s = load(os.path.join(ROOT, "tests", "data", "gradient", "penumbra-sign.xml"), res=8, spp=1)
    params = ["occluder:translate:0,1,0"]
    img, plain = qsil.grad(s, params, spp=16, seed=3, boundary="projective")
    again_img, guided = qsil.grad(s, params, spp=16, seed=3, boundary="projective", guiding_resolution=8)
    assert np.array_equal(img, again_img)  # the guide changes the boundary term only
    assert np.isfinite(plain).all() and np.isfinite(guided).all()
    assert not np.array_equal(plain, guided)  # other segments: the guide reached the estimator
    with pytest.raises(qsil.Error) as e:
        qsil.grad(s, params, boundary="projective", guiding_resolution=65)
    assert "guiding resolution 65 out of range" in str(e.value)
    _, octree = qsil.grad(s, params, spp=16, seed=3, boundary="projective", guiding_octree=True, guiding_seeds=8)
    assert np.isfinite(octree).all() and not np.array_equal(plain, octree) and not np.array_equal(guided, octree)
    with pytest.raises(qsil.Error) as e:
        qsil.grad(s, params, boundary="projective", guiding_octree=True, guiding_resolution=8)
    assert "exclude each other" in str(e.value)


def test_was_grad_reaches_its_auxiliary_rays():
    s = load(os.path.join(ROOT, "tests", "data", "gradient", "penumbra-sign.xml"), res=8, spp=1)
    params = ["occluder:translate:0,1,0"]
    _, eight = qsil.grad(s, params, spp=4, seed=3, boundary="was")
    _, two = qsil.grad(s, params, spp=4, seed=3, boundary="was", was_rays=2, was_kappa=1e3)
    assert np.isfinite(eight).all() and np.isfinite(two).all() and not np.array_equal(eight, two)
    with pytest.raises(qsil.Error) as e:
        qsil.grad(s, params, boundary="was", was_rays=0)
    assert "rays" in str(e.value)


def test_quadric_grad_reaches_its_forest_guide():
    s = load(os.path.join(ROOT, "tests", "data", "gradient", "spot-selfshadow.xml"), res=8, spp=1)
    params = ["spot:translate:1,0,0"]
    _, plain = qsil.grad(s, params, spp=8, seed=3)
    _, guided = qsil.grad(s, params, spp=8, seed=3, forest_guide_training=4, forest_guide_rounds=1,
                          forest_guide_resolution=4, forest_guide_depth=2, forest_guide_share=0.3)
    assert np.isfinite(guided).all() and not np.array_equal(plain, guided)
    with pytest.raises(qsil.Error) as e:
        qsil.grad(s, params, forest_guide_training=4, forest_guide_depth=9)
    assert "forest guide: depth 9 out of range [0, 8]" in str(e.value)


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
