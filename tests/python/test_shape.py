"""python/qsil_shape.py (Large Steps, Nicolet et al. 2021): the Laplacian, the parametrisation's
solve, uniform Adam's step, a convergence oracle and bad input.

Run by ctest with the Python bindings (PYTHONPATH=<build>/python, where the build copies it).
"""
import numpy as np
import pytest

import qsil_shape
from test_bindings import icosphere, mesh_edges


def test_laplacian_is_degree_minus_adjacency():
    v, f = icosphere(0, radius=1.0, centre=(0.0, 0.0, 0.0))  # the icosahedron: every vertex of degree 5
    L = qsil_shape.combinatorial_laplacian(f, len(v)).toarray()
    assert np.allclose(L, L.T) and np.allclose(L.sum(axis=1), 0)
    assert np.array_equal(np.diag(L), np.full(12, 5.0))
    assert set(np.unique(L[~np.eye(12, dtype=bool)])) == {0.0, -1.0}


def test_parametrisation_round_trip_and_solve():
    v, f = icosphere(2, radius=0.5, centre=(0.1, 0.2, 0.3))
    opt = qsil_shape.LargeSteps(v, f, lam=19.0)
    assert np.allclose(opt.positions(), v, atol=1e-10)
    g = np.random.default_rng(1).normal(size=v.shape)
    assert np.allclose(opt.M @ opt.gradient_u(g), g, atol=1e-9)


def test_uniform_adam_first_step_moves_the_largest_element_by_lr():
    v, f = icosphere(1, radius=1.0, centre=(0.0, 0.0, 0.0))
    opt = qsil_shape.LargeSteps(v, f, lr=0.01)
    u0 = opt.u.copy()
    g = np.random.default_rng(2).normal(size=v.shape)
    opt.step(g)
    du = opt.u - u0
    assert np.isclose(np.abs(du).max(), 0.01, rtol=1e-6)
    # The direction is the smoothed gradient's: du is -lr * gu / max|gu|, not per-element Adam's sign.
    gu = opt.gradient_u(g)
    assert np.allclose(du, -0.01 * gu / np.abs(gu).max(), atol=1e-9)


def test_converges_to_a_target_shape():
    # E = |x - x*|^2 / 2 for x* an ellipsoid, from the sphere: the error falls 20-fold in 300 steps.
    v, f = icosphere(2, radius=1.0, centre=(0.0, 0.0, 0.0))
    target = v * np.array([1.3, 0.8, 1.0])
    opt = qsil_shape.LargeSteps(v, f, lam=19.0, lr=0.05)
    e0 = np.abs(v - target).max()
    x = v
    for _ in range(300):
        x = opt.step(x - target)
    assert np.abs(x - target).max() < e0 / 20, np.abs(x - target).max() / e0
    # Still a closed mesh with the same edges (no tangling): every triangle keeps its orientation.
    n0 = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n1 = np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]])
    assert (np.einsum("ij,ij->i", n0, n1) > 0).all()
    assert len(mesh_edges(f)) == 3 * len(f)


def test_remeshed_resets_the_moments_and_scales_lr():
    v, f = icosphere(1, radius=1.0, centre=(0.0, 0.0, 0.0))
    opt = qsil_shape.LargeSteps(v, f, lr=0.02)
    opt.step(np.ones_like(v))
    v2, f2 = icosphere(2, radius=1.0, centre=(0.0, 0.0, 0.0))
    new = opt.remeshed(v2, f2, lr_scale=0.5)
    assert new.lr == 0.01 and new.steps == 0 and not new.m1.any() and new.u.shape == v2.shape


def test_bad_input_raises():
    v, f = icosphere(1, radius=1.0, centre=(0.0, 0.0, 0.0))
    opt = qsil_shape.LargeSteps(v, f)
    for call, needle in [(lambda: opt.step(np.ones((3, 3))), "expected a gradient of shape"),
                         (lambda: opt.step(np.full_like(v, np.nan)), "non-finite"),
                         (lambda: qsil_shape.LargeSteps(v[:, :2], f), "expected positions of shape (V, 3)"),
                         (lambda: qsil_shape.LargeSteps(v, f + len(v)), "outside"),
                         (lambda: qsil_shape.LargeSteps(v, f, lr=0), "lr")]:
        with pytest.raises(ValueError) as e:
            call()
        assert needle in str(e.value)


def test_surface_distance_of_concentric_spheres():
    """Oracle: between spheres of radii 1 and 1.1 every nearest distance is about 0.1 (the
    tessellation's sagitta aside), so Chamfer and Hausdorff are both 0.1 / the diagonal (2, the
    truth's box); a mesh against itself scores below the samples' spacing."""
    v, f = icosphere(4, radius=1.0, centre=(0.0, 0.0, 0.0))
    d = qsil_shape.SurfaceDistance(v, f, n=20000)
    assert np.isclose(d.diag, 2 * np.sqrt(3) * np.abs(v).max(axis=0).mean(), rtol=1e-3)
    chamfer, hausdorff = d(1.1 * v, f)
    assert abs(chamfer - 0.1 / d.diag) < 0.1 * 0.1 / d.diag
    assert 0.1 / d.diag <= hausdorff < 1.3 * 0.1 / d.diag
    self_chamfer, self_hausdorff = d(v, f)
    spacing = np.sqrt(4 * np.pi / 20000)
    assert self_chamfer < spacing / d.diag and self_hausdorff < 3 * spacing / d.diag
    # A shape missing half the truth: Hausdorff sees the missing half (up to sqrt 2, pole to rim).
    half = f[(v[f].mean(axis=1)[:, 2] > 0)]
    assert d(v, half)[1] > 0.8 / d.diag


def test_replace_generated_rewrites_only_its_section(tmp_path):
    page = tmp_path / "page.md"
    begin = qsil_shape.GENERATED_BEGIN % ("rec.json", "script.py")
    page.write_text("# Title\n\nkept\n\n%s\nold\n%s\n\nkept too\n" % (begin, qsil_shape.GENERATED_END))
    qsil_shape.replace_generated(str(page), "rec.json", "script.py", "new | table\n")
    assert page.read_text() == "# Title\n\nkept\n\n%s\nnew | table\n%s\n\nkept too\n" % (
        begin, qsil_shape.GENERATED_END)
    # Another record's markers: an error naming the page, and the page as it was.
    before = page.read_text()
    with pytest.raises(ValueError, match="page.md"):
        qsil_shape.replace_generated(str(page), "other.json", "script.py", "x")
    assert page.read_text() == before


def test_ratio_only_of_positive_values():
    assert qsil_shape.ratio(3e-5, 1e-5) == "3.0×"
    assert all("no ratio" in qsil_shape.ratio(a, b) for a, b in [(-1e-6, 1e-5), (1e-5, 0.0), (float("nan"), 1.0)])


def test_surface_distance_of_a_part():
    """A shape right on one half of the truth and 0.2 off on the other: the part's distances see
    only the half it names."""
    v, f = icosphere(4, radius=1.0, centre=(0.0, 0.0, 0.0))
    d = qsil_shape.SurfaceDistance(v, f, n=20000)
    moved = np.where(v[:, 2:3] > 0, 1.2 * v, v)  # the upper half pushed out by up to 0.2
    lower = d.points[:, 2] < -0.3
    chamfer, hausdorff = d(moved, f, part=lower)
    assert chamfer < 0.01 and hausdorff < 0.03
    whole_chamfer, whole_hausdorff = d(moved, f)
    assert whole_chamfer > 3 * chamfer and whole_hausdorff > 0.15 / d.diag
