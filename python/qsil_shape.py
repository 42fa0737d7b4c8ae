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


# ---- Scoring and reporting, shared by the optimisation demos (examples/).

def mean_edge(V, F):
    """The mean length of the triangles' edges (each interior edge counted twice)."""
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return float(np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1).mean())


def write_obj(path, V, F):
    """Writes positions V (V, 3) and triangles F (T, 3, 0-based) as a Wavefront OBJ."""
    with open(path, "w") as out:
        out.writelines("v %.9g %.9g %.9g\n" % tuple(p) for p in V)
        out.writelines("f %d %d %d\n" % tuple(f + 1) for f in F)


def surface_samples(V, F, n, rng):
    """n points (n, 3) uniform by area on the triangles F (T, 3) of positions V (V, 3); rng: a
    numpy.random.Generator."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    tri = rng.choice(len(F), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    return (1 - s)[:, None] * a[tri] + (s * (1 - r2))[:, None] * b[tri] + (s * r2)[:, None] * c[tri]


class SurfaceDistance:
    """Chamfer and Hausdorff distances from meshes to one true mesh, relative to the true mesh's
    bounding-box diagonal: between n area-uniform samples of each surface (fixed seeds, so that a
    shape's score does not change between calls). Chamfer is the mean of both directions' mean
    nearest-sample distance, Hausdorff the largest nearest-sample distance either way; both are
    estimates whose resolution is about the samples' spacing (sqrt(area / n))."""

    def __init__(self, V, F, n=20000):
        from scipy.spatial import cKDTree
        V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
        self.n = n
        self.diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
        self.points = surface_samples(V, F, n, np.random.default_rng(3))
        self.tree = cKDTree(self.points)

    def __call__(self, V, F, part=None):
        """(chamfer, hausdorff) of the mesh V (V, 3), F (T, 3), as fractions of the diagonal.
        part: None, or a bool mask (n,) over the truth's samples (self.points): then both are of
        that part of the truth and the mesh samples nearest to it (e.g. the part a camera sees)."""
        from scipy.spatial import cKDTree
        if part is not None:
            part = np.asarray(part)
            if part.dtype != bool or part.shape != (self.n,) or not part.any():
                raise ValueError("SurfaceDistance: part must be a non-empty bool mask of shape (%d,)" % self.n)
        pts = surface_samples(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64), self.n,
                              np.random.default_rng(7))
        d_to_truth, nearest = self.tree.query(pts)
        d_from_truth, _ = cKDTree(pts).query(self.points)
        if part is not None:
            d_to_truth, d_from_truth = d_to_truth[part[nearest]], d_from_truth[part]
            if len(d_to_truth) == 0:  # no sample of the mesh is nearest to the part: only one way
                return d_from_truth.mean() / self.diag, d_from_truth.max() / self.diag
        chamfer = 0.5 * (d_to_truth.mean() + d_from_truth.mean())
        return chamfer / self.diag, max(d_to_truth.max(), d_from_truth.max()) / self.diag


class Progress:
    """One status line on a terminal: a bar of the time budget, the step rate and the loss of the
    steps' own renders (an exponential mean over about 20 steps: noisy, since a low-spp render's
    Monte Carlo noise is in it). Silent when the stream is not a terminal (logs, ctest)."""

    def __init__(self, name, seconds, stream=None, width=24):
        import sys
        self.name, self.seconds, self.width = name, float(seconds), width
        self.stream = sys.stderr if stream is None else stream
        self.tty = self.stream.isatty()
        self.loss, self.shown, self.drawn = None, 0.0, False

    def show(self, elapsed, step, loss, note=""):
        """After each step: elapsed seconds, steps taken, that step's loss; note: e.g. the film size."""
        import time
        self.loss = loss if self.loss is None else 0.95 * self.loss + 0.05 * loss
        now = time.perf_counter()
        if not self.tty or now - self.shown < 0.2:
            return
        self.shown = now
        filled = int(self.width * min(1.0, elapsed / self.seconds))
        self.stream.write("\r%-10s [%s%s] %5.0f/%.0f s  step %5d  %5.1f steps/s  %s loss %.5f "
                          % (self.name, "#" * filled, "." * (self.width - filled), elapsed, self.seconds, step,
                             step / max(elapsed, 1e-9), note, self.loss))
        self.stream.flush()
        self.drawn = True

    def clear(self):
        """Ends the status line before other output."""
        if self.drawn:
            self.stream.write("\r" + " " * 110 + "\r")
            self.stream.flush()
            self.drawn = False


GENERATED_BEGIN = "<!-- generated from %s by %s: edit the script, not this text -->"
GENERATED_END = "<!-- end of generated text -->"


def replace_generated(page, record, script, text):
    """Replaces, in the Markdown file `page`, the text between the markers GENERATED_BEGIN (naming
    `record` and `script`) and GENERATED_END with `text`. Raises ValueError, naming the page, when
    the markers are missing; the page is written whole (a temporary file renamed) or left as it was."""
    import os
    begin = GENERATED_BEGIN % (record, script)
    with open(page) as f:
        content = f.read()
    i = content.find(begin)
    j = content.find(GENERATED_END, i + 1) if i >= 0 else -1
    if i < 0 or j < 0:
        raise ValueError("%s: no '%s' ... '%s' section to replace" % (page, begin, GENERATED_END))
    content = content[:i + len(begin)] + "\n" + text.rstrip("\n") + "\n" + content[j:]
    tmp = page + ".tmp"
    with open(tmp, "w") as f:
        f.write(content)
    os.replace(tmp, page)


def progress_chart(path, methods, floor, title, seen=False, targets=None):
    """Writes the chart of a demo's record: for each method (name -> {"steps", "curve"}, a curve's
    rows being (seconds, step, loss, chamfer, hausdorff, vertices[, seen chamfer, seen hausdorff]))
    the image loss above the noise floor `floor` (the true mesh's loss; a dashed line at zero), and
    the Chamfer and Hausdorff distances (fractions, shown in %), against time. The loss axis is
    linear: a scoring render's noise can put a shape's loss below the floor, which a log axis would
    hide. seen: also the seen part's distances (dotted); targets: (chamfer,
    hausdorff) fractions drawn as dashed lines."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for method, r in methods.items():
        c = np.array(r["curve"])
        label = "%s (%d steps)" % (method, r["steps"])
        axes[0].plot(c[:, 0], c[:, 2] - floor, marker="o", label=label)
        for k, ax in ((3, axes[1]), (4, axes[2])):
            line, = ax.plot(c[:, 0], 100 * c[:, k], marker="o", label=label)
            if seen:
                ax.plot(c[:, 0], 100 * c[:, k + 3], ls=":", color=line.get_color(), label=method + ": seen part")
    axes[0].axhline(0.0, color="k", ls="--", lw=0.8, label="noise floor (the true mesh's loss)")
    axes[0].set_ylabel("image loss above the noise floor (%.4g)" % floor)
    axes[1].set_ylabel("Chamfer distance (% of the diagonal)")
    axes[2].set_ylabel("Hausdorff distance (% of the diagonal)")
    if targets is not None:
        for ax, t in zip(axes[1:], targets):
            ax.axhline(100 * t, color="k", ls="--", lw=0.8)
    for a in axes:
        a.set_xlabel("optimisation time (s, 2 threads)")
        a.legend()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def add_page_arguments(ap):
    """A demo's --page and --page-from options (argparse.ArgumentParser ap)."""
    ap.add_argument("--page", help="Markdown page whose generated section (markers: replace_generated) is rewritten "
                                   "from the record after the run, e.g. docs/inverse-rendering.md")
    ap.add_argument("--page-from", metavar="RECORD",
                    help="no optimisation: rewrite --page's generated section from this results.json")


def page_from_record(ap, args, record, script, page_text):
    """With --page-from: rewrites --page's section for `record` from that file through
    page_text(record dict) and returns True (the demo then stops); False otherwise."""
    import json
    if not args.page_from:
        return False
    if not args.page:
        ap.error("--page-from needs --page")
    with open(args.page_from) as f:
        replace_generated(args.page, record, script, page_text(json.load(f)))
    print("rewrote the generated section of %s from %s" % (args.page, args.page_from))
    return True


def write_record(args, results, record, script, page_text):
    """After a demo's run: results.json (the record) and report.md (page_text of it) in args.out,
    the text printed, and with --page the page's section for `record` rewritten."""
    import json
    import os
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    text = page_text(results)
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(text)
    print(text)
    if args.page:
        replace_generated(args.page, record, script, text)
        print("rewrote the generated section of", args.page)


def ratio(a, b):
    """'a/b×' for a report, or 'no ratio' when either is not positive and finite (a loss at or
    below its noise floor, a zero distance)."""
    ok = np.isfinite(a) and np.isfinite(b) and a > 0 and b > 0
    return "%.1f×" % (a / b) if ok else "no ratio: a value at or below zero"
