/// @file enclosing_sphere.cpp
/// Welzl's smallest enclosing sphere with move-to-front and the extremal-points approximation
/// [QSS 4.4, Appendix G].

#include "enclosing_sphere.h"
#include "extremes.h"

#include <algorithm>
#include <cmath>
#include <list>

namespace qsil::edgetree {

bool Sphere::contains(const Vec3& p) const {
  if (radius < 0.0) return false;
  const double r = radius * (1.0 + 1e-12) + 1e-300;
  return (p - center).squaredNorm() <= r * r;
}

namespace {

Sphere sphere_of_two(const Vec3& a, const Vec3& b) { return {0.5 * (a + b), 0.5 * (a - b).norm()}; }

// Circumscribed sphere of the support points (1 to 4). Returns radius < 0 if degenerate.
Sphere sphere_of_support(const Vec3* s, int n) {
  if (n == 0) return {};
  if (n == 1) return {s[0], 0.0};
  if (n == 2) return sphere_of_two(s[0], s[1]);
  if (n == 3) {
    const Vec3 a = s[1] - s[0], b = s[2] - s[0];
    const Vec3 axb = a.cross(b);
    const double den = 2.0 * axb.squaredNorm();
    if (!(den > 1e-30 * a.squaredNorm() * b.squaredNorm()) || den == 0.0) return {};
    const Vec3 off = (a.squaredNorm() * b.cross(axb) + b.squaredNorm() * axb.cross(a)) / den;
    return {s[0] + off, off.norm()};
  }
  // n == 4: 2 (p_i - p0) . c' = |p_i - p0|^2, i = 1..3.
  Mat3 M;
  Vec3 rhs;
  for (int i = 0; i < 3; ++i) {
    const Vec3 d = s[i + 1] - s[0];
    M.row(i) = 2.0 * d.transpose();
    rhs[i] = d.squaredNorm();
  }
  const double det = M.determinant();
  const double scale = M.row(0).norm() * M.row(1).norm() * M.row(2).norm();
  if (!(std::abs(det) > 1e-14 * scale)) return {};
  const Vec3 off = M.partialPivLu().solve(rhs);
  if (!off.allFinite()) return {};
  return {s[0] + off, off.norm()};
}

// Smallest sphere of a degenerate support set: the best sphere of a subset that covers all.
Sphere degenerate_support(const Vec3* s, int n) {
  Sphere best;
  best.radius = kInf;
  for (int mask = 1; mask < (1 << n); ++mask) {
    Vec3 sub[4];
    int k = 0;
    for (int i = 0; i < n; ++i)
      if (mask & (1 << i)) sub[k++] = s[i];
    if (k == n) continue;
    Sphere c = sphere_of_support(sub, k);
    if (c.radius < 0.0) continue;
    bool ok = true;
    for (int i = 0; i < n && ok; ++i) ok = c.contains(s[i]);
    if (ok && c.radius < best.radius) best = c;
  }
  if (!std::isfinite(best.radius)) best = sphere_of_two(s[0], s[n - 1]);
  return best;
}

struct MtfSolver {
  std::list<Vec3> pts;
  Vec3 support[4];
  int ns = 0;
  Sphere ball;

  void solve(std::list<Vec3>::iterator end) {
    ball = sphere_of_support(support, ns);
    if (ball.radius < 0.0 && ns > 0) ball = degenerate_support(support, ns);
    if (ns == 4) return;
    for (auto it = pts.begin(); it != end;) {
      auto next = std::next(it);
      if (!ball.contains(*it)) {
        support[ns++] = *it;
        solve(it);
        --ns;
        pts.splice(pts.begin(), pts, it);  // move to front
      }
      it = next;
    }
  }
};

Sphere grow_to_cover(Sphere s, std::span<const Vec3> points) {
  for (const Vec3& p : points) {
    if (s.radius < 0.0) {
      s = {p, 0.0};
      continue;
    }
    const double d = (p - s.center).norm();
    if (d > s.radius) {
      const double r = 0.5 * (s.radius + d);
      s.center += ((r - s.radius) / d) * (p - s.center);
      // Rounding guard: the radius covers both the point and the old sphere.
      s.radius = std::max(r, (p - s.center).norm()) * (1.0 + 4e-16);
    }
  }
  return s;
}

}  // namespace

Sphere min_enclosing_sphere(std::span<const Vec3> points) {
  if (points.empty()) return {};
  MtfSolver solver;
  solver.pts.assign(points.begin(), points.end());
  solver.solve(solver.pts.end());
  return grow_to_cover(solver.ball, points);
}

const std::vector<Vec3>& extremal_directions() {
  // 16 directions on the upper hemisphere by a Fibonacci spiral (z from ~1 down to ~0).
  static const std::vector<Vec3> dirs = [] {
    std::vector<Vec3> d;
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < 16; ++i) {
      const double z = 1.0 - (i + 0.5) / 16.0;
      const double r = std::sqrt(1.0 - z * z);
      d.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
    }
    return d;
  }();
  return dirs;
}

Sphere approx_enclosing_sphere(std::span<const Vec3> points) {
  if (points.empty()) return {};
  const auto& dirs = extremal_directions();
  std::vector<Vec3> ext;
  ext.reserve(32);
  if (points.size() <= 32) {
    ext.assign(points.begin(), points.end());
  } else {
    for (const Vec3& d : dirs) {
      const auto [imin, imax] = extreme_indices(points.size(), [&](size_t i) { return d.dot(points[i]); });
      ext.push_back(points[imin]);
      ext.push_back(points[imax]);
    }
  }
  MtfSolver solver;
  solver.pts.assign(ext.begin(), ext.end());
  solver.solve(solver.pts.end());
  return grow_to_cover(solver.ball, points);
}

}  // namespace qsil::edgetree
