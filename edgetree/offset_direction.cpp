/// @file offset_direction.cpp
/// Offset direction D and basis A [QSS 3.2, 4.4].

#include "offset_direction.h"

#include "enclosing_sphere.h"
#include "offset_lp.h"

#include <cmath>
#include <vector>

namespace qsil::edgetree {

namespace {
// min over planes of (D.q) / (|D| |q|); NaN-safe (returns -inf on NaN).
double min_cosine(std::span<const Vec4> planes, const Vec4& D) {
  const double dn = D.norm();
  if (!(dn > 0.0)) return -kInf;
  double m = kInf;
  for (const Vec4& q : planes) {
    const double c = D.dot(q) / (dn * q.norm());
    if (!(c >= -kInf)) return -kInf;  // NaN
    m = std::min(m, c);
  }
  return m;
}

bool from_sphere(const Sphere& s, std::span<const Vec4> planes, OffsetDirection* out) {
  if (!(s.radius >= 0.0 && s.radius < 1.0)) return false;
  const double cn = s.center.norm();
  if (!(cn > 0.0)) return false;
  Vec4 D;
  D << s.center / cn, 0.0;
  const double mc = min_cosine(planes, D);
  if (!(mc > kMinZq)) return false;
  out->kind = OffsetDirection::Kind::Direction;
  out->D = D;
  out->min_cos = mc;
  return true;
}
}  // namespace

OffsetDirection choose_offset_direction(std::span<const Vec4> planes) {
  OffsetDirection out;
  if (planes.empty()) return out;
  std::vector<Vec3> normals;
  normals.reserve(planes.size());
  for (const Vec4& q : planes) normals.push_back(q.head<3>());

  // 1. Approximate smallest enclosing sphere [QSS 4.4].
  if (from_sphere(approx_enclosing_sphere(normals), planes, &out)) return out;

  // 2. The LP [QSS Eq. 6]: a point in front of every plane.
  out.used_lp = true;
  const OffsetLpResult lp = solve_offset_lp(planes);
  if (lp.status == OffsetLpResult::Status::Optimal && lp.rho > 0.0 && lp.point.allFinite()) {
    Vec4 D;
    D << lp.point, 1.0;
    const double mc = min_cosine(planes, D);
    if (mc > kMinZq) {
      out.kind = OffsetDirection::Kind::Point;
      out.D = D;
      out.min_cos = mc;
      return out;
    }
  }
  // 3. Unbounded (a direction exists that the approximate sphere missed) or a failed solve:
  // the exact smallest enclosing sphere over every normal (docs/architecture.md §5).
  if (lp.status != OffsetLpResult::Status::Optimal && from_sphere(min_enclosing_sphere(normals), planes, &out))
    return out;
  // Infeasible, rho <= 0, or unbounded while even the exact sphere found no direction (only at
  // the edge of feasibility, where min cos would be ~0 anyway): never reject [QSS App. B].
  out.kind = OffsetDirection::Kind::Unrejectable;
  return out;
}

Mat4 basis_from_direction(const Vec4& D) {
  const Vec4 Z = D.normalized();
  int k = 0;
  Z.cwiseAbs().maxCoeff(&k);
  // Householder H = I - 2 v v^T / v.v with v = Z + sign(Z_k) e_k maps e_k to -sign(Z_k) Z.
  Vec4 v = Z;
  const double sg = Z[k] >= 0.0 ? 1.0 : -1.0;
  v[k] += sg;
  const Mat4 H = Mat4::Identity() - (2.0 / v.squaredNorm()) * v * v.transpose();
  Mat4 A;
  int c = 0;
  for (int i = 0; i < 4; ++i)
    if (i != k) A.col(c++) = H.col(i);
  A.col(3) = Z;
  return A;
}

}  // namespace qsil::edgetree
