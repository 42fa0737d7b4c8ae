#pragma once
/// @file ray_hits.h
/// Ray-primitive intersection oracles for tests: independent of the library's own geometry code
/// (the tests use them to judge it). Rays start at the origin unless an origin is given;
/// directions need not be unit.

#include "qsil/math.h"
#include "qsil/scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

namespace qsil::test {

/// Whether the ray from the origin along d hits the quad c (corners in order; two triangles,
/// Möller-Trumbore without culling, hits at positive distance only).
inline bool ray_hits_quad(const Vec3& d, const std::array<Vec3, 4>& c) {
  auto tri = [&](const Vec3& a, const Vec3& b, const Vec3& e) {
    const Vec3 e1 = b - a, e2 = e - a, pv = d.cross(e2);
    const double det = e1.dot(pv);
    if (std::abs(det) < 1e-300) return false;
    const Vec3 tv = -a;
    const double u = tv.dot(pv) / det;
    if (u < 0 || u > 1) return false;
    const Vec3 qv = tv.cross(e1);
    const double v = d.dot(qv) / det;
    if (v < 0 || u + v > 1) return false;
    return e2.dot(qv) / det > 0;
  };
  return tri(c[0], c[1], c[2]) || tri(c[0], c[2], c[3]);
}

/// Whether the ray from the origin along d meets the axis-aligned box [lo, hi] at a positive
/// distance (slab test).
inline bool ray_hits_box(const Vec3& d, const Vec3& lo, const Vec3& hi) {
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0) {  // parallel to the slab: inside it or never
      if (lo[i] > 0 || hi[i] < 0) return false;
      continue;
    }
    double a = lo[i] / d[i], b = hi[i] / d[i];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t0 <= t1;
}

/// The nearest hit of a ray with a mesh: the face and the distance along d (in units of |d|).
struct MeshHit {
  int face = -1;  ///< index into TriangleMesh::triangles
  double t = 0;   ///< the hit is o + t d, t > 0
};

/// The nearest hit at t > 0 of the ray o + t d with `m` (brute force over its triangles,
/// Möller-Trumbore without culling; triangles with |det| < 1e-14 skipped), or nullopt.
inline std::optional<MeshHit> ray_hits_mesh(const Vec3& o, const Vec3& d, const TriangleMesh& m) {
  std::optional<MeshHit> best;
  for (int f = 0; f < m.num_triangles(); ++f) {
    const auto& tri = m.triangles[size_t(f)];
    const Vec3 &p0 = m.positions[size_t(tri[0])], &p1 = m.positions[size_t(tri[1])], &p2 = m.positions[size_t(tri[2])];
    const Vec3 e1 = p1 - p0, e2 = p2 - p0, q = d.cross(e2);
    const double det = e1.dot(q);
    if (std::abs(det) < 1e-14) continue;
    const Vec3 s = o - p0;
    const double u = s.dot(q) / det;
    const Vec3 r = s.cross(e1);
    const double v = d.dot(r) / det, t = e2.dot(r) / det;
    if (u >= 0 && v >= 0 && u + v <= 1 && t > 0 && (!best || t < best->t)) best = MeshHit{f, t};
  }
  return best;
}

}  // namespace qsil::test
