/// @file node_rejection.cpp
/// Node rejection test [QSS 3.4, Appendix C].

#include "qsil/edgetree/node_rejection.h"

#include "conic.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace qsil::edgetree {

namespace {

/// A strictly increasing function of atan2(v.y, v.x) on [0, 2 pi), with values in [0, 4) (the
/// "diamond angle": the position along the unit L1 circle). Sorting by it orders points by angle
/// as atan2 does, up to a cyclic shift, at the cost of one division; v = 0 gives 0.
double pseudo_angle(const Vec2& v) {
  const double x = v.x(), y = v.y();
  if (x == 0.0 && y == 0.0) return 0.0;
  if (y >= 0.0) return x >= 0.0 ? y / (x + y) : 1.0 - x / (y - x);
  return x < 0.0 ? 2.0 - y / (-x - y) : 3.0 + x / (x - y);
}

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Sign-change or touching test of the quadratic f(t) = A t^2 + B t + F on [0,1] with end values
// F and Fe (Fe = f(1), computed directly), tolerance tol: true if f has a root in [0,1] up to tol.
bool quadratic_has_root(double A, double B, double F, double Fe, double tol) {
  if ((F <= tol && Fe >= -tol) || (F >= -tol && Fe <= tol)) return true;
  if (F > tol && Fe > tol) {  // both positive: an interior minimum <= 0?
    if (A > 0.0 && -B > 0.0 && -B < 2.0 * A) return 4.0 * A * F - B * B <= 4.0 * A * tol;
    return false;
  }
  if (F < -tol && Fe < -tol) {  // both negative: an interior maximum >= 0?
    if (A < 0.0 && B > 0.0 && B < -2.0 * A) return 4.0 * A * F - B * B <= -4.0 * A * tol;
    return false;
  }
  return true;  // NaN
}
/// The dual plane [r,1].a = 0 (a in the bound's basis, local frame) over the dual box B_q: the
/// range [fmin, fmax] of its value, the magnitude fmag of its terms, and rb = max |B_q|.
struct PlaneOverBox {
  double fmin, fmax, fmag, rb;
};

PlaneOverBox plane_over_box(const NodeBound& b, const Vec4& a) {
  double fmin = a[3], fmax = a[3], fmag = std::abs(a[3]);
  double rb = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double u = a[i] * b.bq_lo[i], v = a[i] * b.bq_hi[i];
    fmin += std::min(u, v);
    fmax += std::max(u, v);
    fmag += std::max(std::abs(u), std::abs(v));
    rb = std::max({rb, std::abs(b.bq_lo[i]), std::abs(b.bq_hi[i])});
  }
  return {fmin, fmax, fmag, rb};
}

/// The points where the plane an.r + a3 = 0 meets the 12 edges of B_q (corners on the plane
/// included), at most 12, in `pts`; returns how many.
int plane_box_section(const NodeBound& b, const Vec3& an, double a3, std::array<Vec3, 12>& pts) {
  std::array<Vec3, 8> corner;
  std::array<double, 8> fc;
  for (int k = 0; k < 8; ++k) {
    corner[k] =
        Vec3(k & 1 ? b.bq_hi.x() : b.bq_lo.x(), k & 2 ? b.bq_hi.y() : b.bq_lo.y(), k & 4 ? b.bq_hi.z() : b.bq_lo.z());
    fc[k] = an.dot(corner[k]) + a3;
  }
  int np = 0;
  for (int k = 0; k < 8; ++k) {
    if (fc[k] == 0.0 && np < 12) pts[np++] = corner[k];
    for (int bit = 1; bit < 8; bit <<= 1) {
      const int j = k | bit;
      if (j == k) continue;
      if ((fc[k] < 0.0 && fc[j] > 0.0) || (fc[k] > 0.0 && fc[j] < 0.0)) {
        const double t = fc[k] / (fc[k] - fc[j]);
        if (np < 12) pts[np++] = corner[k] + t * (corner[j] - corner[k]);
      }
    }
  }
  return np;
}

/// The convex polygon C in its plane: 2D vertices v[0, nv) in the basis (pf.s, pf.t), origin o.
struct PlanePolygon {
  Frame pf;
  Vec3 o;
  std::array<Vec2, 12> v;
  int nv = 0;
};

/// The polygon of the np points `pts` in the plane of unit normal `normal`, origin at their mean
/// (inside the convex polygon), sorted by angle with (near-)duplicates dropped.
PlanePolygon plane_polygon(const Vec3& normal, const std::array<Vec3, 12>& pts, int np) {
  PlanePolygon g;
  g.pf = Frame(normal);
  const Frame& pf = g.pf;
  Vec3 o = Vec3::Zero();
  for (int i = 0; i < np; ++i) o += pts[i];
  o /= np;
  g.o = o;
  std::array<Vec2, 12> poly;
  std::array<double, 12> ang;
  std::array<int, 12> order;
  double diam = 0.0;
  for (int i = 0; i < np; ++i) {
    const Vec3 d = pts[i] - o;
    poly[i] = Vec2(pf.s.dot(d), pf.t.dot(d));
    ang[i] = pseudo_angle(poly[i]);
    order[i] = i;
    diam = std::max(diam, poly[i].norm());
  }
  std::sort(order.begin(), order.begin() + np, [&](int i, int j) { return ang[i] < ang[j]; });
  std::array<Vec2, 12>& v = g.v;
  int nv = 0;
  for (int k = 0; k < np; ++k) {
    const Vec2& q = poly[order[k]];
    if (nv > 0 && (q - v[nv - 1]).norm() <= 1e-12 * diam) continue;
    v[nv++] = q;
  }
  while (nv > 1 && (v[nv - 1] - v[0]).norm() <= 1e-12 * diam) --nv;
  g.nv = nv;
  return g;
}

/// Conic of Q~0 = G0 in the polygon's plane: [r,1] = P [alpha, 1], P = [[u1, u2, o], [0, 0, 1]].
Mat3 plane_conic(const Mat4& G0, const PlanePolygon& g) {
  Eigen::Matrix<double, 4, 3> P = Eigen::Matrix<double, 4, 3>::Zero();
  P.block<3, 1>(0, 0) = g.pf.s;
  P.block<3, 1>(0, 1) = g.pf.t;
  P.block<3, 1>(0, 2) = g.o;
  P(3, 2) = 1.0;
  Mat3 C0 = P.transpose() * G0 * P;
  C0 = 0.5 * (C0 + C0.transpose()).eval();
  return C0;
}

/// Steps 2-4: whether Q~0 <= 0 <= Q~1 = Q~0 + delta somewhere on the polygon v (C0: the conic
/// of Q~0 in its plane), up to kappa.
bool conics_meet_polygon(const Mat3& C0, double delta, double kappa, std::span<const Vec2> v) {
  const int nv = int(v.size());
  // ---- 2. a vertex with Q~0 <= 0 <= Q~1 = Q~0 + delta
  std::array<double, 12> h;
  for (int i = 0; i < nv; ++i) {
    h[i] = conic_value(C0, v[i]);
    if (h[i] <= kappa && h[i] + delta >= -kappa) return true;
    if (!std::isfinite(h[i])) return true;
  }
  // ---- 3. a root of Q~0 or Q~1 on an edge
  const int ne = nv == 2 ? 1 : (nv >= 3 ? nv : 0);
  for (int i = 0; i < ne; ++i) {
    const int j = (i + 1) % nv;
    const Vec2 d = v[j] - v[i];
    const double A = d.dot(C0.topLeftCorner<2, 2>() * d);
    const double B = 2.0 * (v[i].dot(C0.topLeftCorner<2, 2>() * d) + C0.block<1, 2>(2, 0) * d);
    if (quadratic_has_root(A, B, h[i], h[j], kappa)) return true;
    if (quadratic_has_root(A, B, h[i] + delta, h[j] + delta, kappa)) return true;
  }
  // ---- 4. a point of either conic inside C [QSS Appendix C]
  if (nv >= 3) {
    const std::span<const Vec2> polygon = v;
    for (int k = 0; k < 2; ++k) {
      Mat3 C = C0;
      if (k == 1) C(2, 2) += delta;
      std::array<Vec2, 4> cp;
      const int n = find_conic_points(C, &cp);
      for (int i = 0; i < n; ++i)
        if (point_in_convex_polygon(polygon, cp[i])) return true;
    }
  }
  return false;
}
}  // namespace

bool bound_may_have_silhouette(const NodeBound& b, bool box_only, const Vec3& p) {
  const LocalFrame& fr = b.frame;
  const Vec4 x = fr.point(p);
  if (!x.allFinite()) return true;
  // Rounding of the world-frame ground truth (q.x evaluated with |p|, |c| ~ m s): relative
  // tolerance grows with the world magnitude expressed in local units.
  const double m = 1.0 + (p.cwiseAbs().maxCoeff() + fr.center.cwiseAbs().maxCoeff()) / fr.scale;
  const double rel = kRejectTol + 64.0 * kEps * m;
  const Vec4 a = b.A.transpose() * x;

  // ---- 1. does the dual plane [r,1].a = 0 meet the box B_q?
  const PlaneOverBox f = plane_over_box(b, a);
  const double rb = f.rb;
  const double ftol = rel * (f.fmag + rb + 1.0);
  if (!(std::isfinite(f.fmin) && std::isfinite(f.fmax) && std::isfinite(ftol))) return true;
  if (f.fmin > ftol || f.fmax < -ftol) return false;
  if (box_only) return true;

  // ---- polygon C: the plane's intersections with the box's 12 edges
  const Vec3 an = a.head<3>();
  const double an_norm = an.norm();
  if (!(an_norm > 0.0)) return true;
  std::array<Vec3, 12> pts;
  const int np = plane_box_section(b, an, a[3], pts);
  if (np == 0) return true;  // touches within tolerance only: degenerate, accept

  // 2D coordinates in the plane, origin at the vertices' mean (inside the convex polygon).
  const PlanePolygon g = plane_polygon(an / an_norm, pts, np);

  // Conic of Q~0 in the plane: [r,1] = P [alpha, 1], P = [[u1, u2, o], [0, 0, 1]].
  const Mat3 C0 = plane_conic(b.G0, g);
  const double delta = b.delta;
  const double R1 = 3.0 * rb + 1.0;
  const double kappa = rel * (b.G0.cwiseAbs().maxCoeff() * 16.0 * R1 * R1 + delta);
  if (!(C0.allFinite() && std::isfinite(kappa))) return true;

  // ---- 2.-4. a vertex, an edge or an interior point of C where Q~0 <= 0 <= Q~1
  if (conics_meet_polygon(C0, delta, kappa, std::span<const Vec2>(g.v.data(), size_t(g.nv)))) return true;
  // ---- 5. no plane of the bound is incident to p
  return false;
}

bool leaf_has_silhouette(const EdgeSet& edges, int leaf, const Vec3& p) {
  for (const Edge& e : edges.leaf_edges(leaf))
    if (edge_is_silhouette(e, p)) return true;
  return false;
}

bool may_have_silhouette(const EdgeForest& forest, int node, const Vec3& p, NodeTest test) {
  const ForestNode& n = forest.node(node);
  if (n.always()) return true;  // an always-candidate tree: no rejection
  if (n.is_leaf()) return leaf_has_silhouette(forest, node, p);
  if (n.unrejectable() || n.bound < 0) return true;
  return bound_may_have_silhouette(forest.bounds()[size_t(n.bound)], test == NodeTest::DualBox || n.box_only(), p);
}

bool node_has_silhouette(const EdgeSet& edges, int node, const Vec3& p) {
  for (const Edge& e : edges.node_edges(node))
    if (edge_is_silhouette(e, p)) return true;
  return false;
}

}  // namespace qsil::edgetree
