/// @file conic.cpp
/// Point on a conic (line and polar line) and convex point-in-polygon [QSS Appendix C].

#include "conic.h"

#include <cmath>

namespace qsil::edgetree {

namespace {
// Real roots t of (r + t e)^T C (r + t e) = 0 for a finite point r = [r, 1] and a direction
// e = [e, 0]; appends the finite points r + t e.
void intersect_line(const Mat3& C, const Vec2& r2, const Vec2& e2, std::array<Vec2, 4>* out, int* n) {
  const Eigen::Vector3d r(r2.x(), r2.y(), 1.0), e(e2.x(), e2.y(), 0.0);
  const Eigen::Vector3d Cr = C * r;
  const double c0 = r.dot(Cr), c1 = 2.0 * e.dot(Cr), c2 = e.dot(C * e);
  if (!(std::isfinite(c0) && std::isfinite(c1) && std::isfinite(c2))) return;
  if (c0 == 0.0) {
    (*out)[(*n)++] = r2;
    return;
  }
  double disc = c1 * c1 - 4.0 * c2 * c0;
  if (disc < 0.0) {
    if (disc >= -kConicTol * (c1 * c1 + 4.0 * std::abs(c2 * c0)))
      disc = 0.0;  // tangent
    else
      return;
  }
  if (c2 == 0.0) {
    if (c1 != 0.0) (*out)[(*n)++] = r2 - (c0 / c1) * e2;
    return;
  }
  // Stable roots: q = -(c1 + sign(c1) sqrt(disc)) / 2, t1 = q / c2, t2 = c0 / q.
  const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
  const double t1 = q / c2;
  if (std::isfinite(t1)) (*out)[(*n)++] = r2 + t1 * e2;
  if (q != 0.0) {
    const double t2 = c0 / q;
    if (std::isfinite(t2)) (*out)[(*n)++] = r2 + t2 * e2;
  }
}
}  // namespace

int find_conic_points(const Mat3& C, std::array<Vec2, 4>* out) {
  int n = 0;
  // Line l through r = origin, direction (1, 0).
  intersect_line(C, Vec2::Zero(), Vec2(1.0, 0.0), out, &n);
  if (n > 0) return n;
  // Polar line l' = C r of r = (0, 0, 1): l'0 x + l'1 y + l'2 = 0.
  const Eigen::Vector3d l = C.col(2);
  const double nn = l.x() * l.x() + l.y() * l.y();
  if (!(nn > 0.0) || !std::isfinite(nn)) return 0;  // l' is the line at infinity
  const Vec2 foot(-l.x() * l.z() / nn, -l.y() * l.z() / nn);
  const Vec2 dir = Vec2(-l.y(), l.x()) / std::sqrt(nn);
  intersect_line(C, foot, dir, out, &n);
  return n;
}

bool point_in_convex_polygon(std::span<const Vec2> poly, const Vec2& a) {
  const int n = int(poly.size());
  if (n < 3) return false;
  double area2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec2& u = poly[i];
    const Vec2& v = poly[(i + 1) % n];
    area2 += u.x() * v.y() - u.y() * v.x();
  }
  const double orient = area2 >= 0.0 ? 1.0 : -1.0;
  for (int i = 0; i < n; ++i) {
    const Vec2 e = poly[(i + 1) % n] - poly[i];
    const Vec2 w = a - poly[i];
    const double cr = orient * (e.x() * w.y() - e.y() * w.x());
    const double tol = 1e-9 * e.norm() * (w.norm() + e.norm());
    if (cr < -tol) return false;
  }
  return true;
}

}  // namespace qsil::edgetree
