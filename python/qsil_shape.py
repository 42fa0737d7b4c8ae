"""Shape optimisation with qsil's gradients: the parametrisation and optimiser of Nicolet et al.
2021, "Large Steps in Inverse Rendering of Geometry" (ACM TOG 40(6)), with remeshing between
stages (qsil.remesh, CGAL's isotropic remeshing).

- The vertex positions x (V, 3) are optimised through u = (I + lam L) x, L the combinatorial
  Laplacian of the mesh (L = D - A, degree minus adjacency). A gradient dE/dx becomes
  dE/du = (I + lam L)^-1 dE/dx (the matrix is symmetric positive definite). So a step in u
  moves x by a smooth field, and the mesh stays smooth at large steps. Section 4 of the paper.
- The steps follow its "uniform Adam". Adam's first moment is divided by the largest square root
  of the second moment over the whole tensor instead of element by element. Then the step keeps
  the direction that the parametrisation smoothed. Section 4.3.

The system is factorised once per mesh (SciPy's sparse LU). `remeshed()` returns an optimiser
for a new mesh, with the moments reset and the learning rate scaled, as the paper's schedule does.

Usage (reverse mode gives dE/dx per vertex):
    opt = LargeSteps(V, F, lr=0.01)
    for step in range(n):
        V = opt.positions()
        g = qsil.reverse(scene, ["shape"], adjoint, ...)["gradient"]["shape"]
        opt.step(g)
    V, F = qsil.remesh(opt.positions(), F, target)   # then
    opt = opt.remeshed(V, F, lr_scale=0.5)
"""
import numpy as np
import scipy.sparse
import scipy.sparse.linalg


def icosphere(subdivisions, centre=(0.0, 0.0, 0.0), radius=1.0):
    """Vertices (V, 3) and counter-clockwise (outward) triangles (T, 3) of the icosahedron with each
    triangle split in four `subdivisions` times, the new vertices pushed onto the sphere: the usual
    start of a shape optimisation. 12 + 10 (4^s - 1) vertices, 20 * 4^s triangles."""
    t = (1.0 + 5.0 ** 0.5) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        midpoints, split = {}, []

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in midpoints:
                m = v[a] + v[b]
                v.append(m / np.linalg.norm(m))
                midpoints[key] = len(v) - 1
            return midpoints[key]

        for a, b, c in f:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = split
    return np.array(v) * radius + np.asarray(centre, dtype=np.float64), np.array(f, dtype=np.int64)


def combinatorial_laplacian(F, n):
    """L = D - A (n x n, CSR) of a triangle mesh's edge graph: triangles F (T, 3), n vertices."""
    F = np.asarray(F, dtype=np.int64)
    if F.ndim != 2 or F.shape[1] != 3 or len(F) == 0:
        raise ValueError("combinatorial_laplacian: expected triangles of shape (T, 3), T >= 1")
    if F.min() < 0 or F.max() >= n:
        raise ValueError(f"combinatorial_laplacian: a triangle refers to a vertex outside [0, {n})")
    i = np.concatenate([F[:, 0], F[:, 1], F[:, 2], F[:, 1], F[:, 2], F[:, 0]])
    j = np.concatenate([F[:, 1], F[:, 2], F[:, 0], F[:, 0], F[:, 1], F[:, 2]])
    A = scipy.sparse.coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n)).tocsr()
    A.data[:] = 1.0  # an edge shared by two triangles counts once
    return (scipy.sparse.diags(np.asarray(A.sum(axis=1)).ravel()) - A).tocsr()


class LargeSteps:
    """Vertex positions x (V, 3) optimised through u = (I + lam L) x with uniform Adam.

    lam: the smoothing weight (the issue's and the paper's examples use about 19); lr: step size
    in units of u; betas, eps: Adam's. Raises ValueError for arrays of the wrong shape or a
    non-finite gradient (a NaN would otherwise spread to every vertex through the solve).
    """

    def __init__(self, V, F, lam=19.0, lr=1e-2, betas=(0.9, 0.999), eps=1e-8):
        V = np.array(V, dtype=np.float64)
        if V.ndim != 2 or V.shape[1] != 3:
            raise ValueError("LargeSteps: expected positions of shape (V, 3)")
        if not (lam >= 0 and lr > 0):
            raise ValueError(f"LargeSteps: lam {lam} must be >= 0 and lr {lr} > 0")
        self.F = np.array(F, dtype=np.int64)
        self.lam, self.lr, self.betas, self.eps = float(lam), float(lr), betas, float(eps)
        n = len(V)
        self.M = (scipy.sparse.identity(n, format="csr") + self.lam * combinatorial_laplacian(self.F, n)).tocsc()
        self._solve = scipy.sparse.linalg.factorized(self.M)
        self.u = self.M @ V
        self.m1 = np.zeros_like(self.u)
        self.m2 = np.zeros_like(self.u)
        self.steps = 0

    def positions(self):
        """The current x = (I + lam L)^-1 u, (V, 3)."""
        return np.stack([self._solve(self.u[:, k]) for k in range(3)], axis=1)

    def gradient_u(self, grad_x):
        """dE/du = (I + lam L)^-1 dE/dx (the matrix is symmetric)."""
        g = np.asarray(grad_x, dtype=np.float64)
        if g.shape != self.u.shape:
            raise ValueError(f"LargeSteps.step: expected a gradient of shape {self.u.shape}, got {g.shape}")
        if not np.isfinite(g).all():
            raise ValueError("LargeSteps.step: the gradient has a non-finite value")
        return np.stack([self._solve(g[:, k]) for k in range(3)], axis=1)

    def step(self, grad_x):
        """One uniform-Adam step on u from dE/dx (V, 3); returns the new positions."""
        g = self.gradient_u(grad_x)
        b1, b2 = self.betas
        self.steps += 1
        self.m1 = b1 * self.m1 + (1 - b1) * g
        self.m2 = b2 * self.m2 + (1 - b2) * g * g
        m1 = self.m1 / (1 - b1 ** self.steps)
        m2 = self.m2 / (1 - b2 ** self.steps)
        self.u = self.u - self.lr * m1 / (self.eps + np.sqrt(m2).max())
        return self.positions()

    def remeshed(self, V, F, lr_scale=1.0):
        """An optimiser for a new mesh (after qsil.remesh): same lam and betas, lr times lr_scale,
        moments reset (they belonged to the old vertices)."""
        return LargeSteps(V, F, lam=self.lam, lr=self.lr * lr_scale, betas=self.betas, eps=self.eps)
