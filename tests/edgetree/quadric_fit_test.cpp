/// @file quadric_fit_test.cpp
/// Dual quadric fit [QSS 4.3, Eq. 5] and the closed-form offsets [QSS 4.2, Appendix D].
/// Tolerances: exact tangent planes are recovered to 1e-8 (relative, Frobenius, after scale and
/// sign normalisation); lambda extrema match a dense search refined by golden section to 1e-9
/// relative to the largest |lambda| on the wedge. Fixed seeds.

#include "edgetree/quadric_fit.h"
#include "edgetree/extremes.h"
#include "edgetree/quadric_offsets.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace qsil::edgetree {
namespace {

// Normalises a symmetric matrix to unit Frobenius norm with a positive (3,3) entry (or the sign
// of its largest entry).
Mat4 normalised(const Mat4& Q) {
  int r, c;
  Q.cwiseAbs().maxCoeff(&r, &c);
  return Q / (Q.norm() * (Q(r, c) >= 0 ? 1.0 : -1.0));
}

// Planes tangent to the ellipsoid {x : (x-m)^T E (x-m) = 1}: q = [n, -(n.m) - sqrt(n^T E^-1 n)].
// Its dual quadric: (n.m + w)^2 = n^T E^-1 n, i.e. Q = [[m m^T - E^-1, m], [m^T, 1]].
void check_ellipsoid(const Mat3& E, const Vec3& m, unsigned seed, int count) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  const Mat3 Ei = E.inverse();
  std::vector<Vec4> planes;
  for (int i = 0; i < count; ++i) {
    Vec3 n(g(rng), g(rng), g(rng));
    n.normalize();
    planes.push_back(Vec4(n.x(), n.y(), n.z(), -n.dot(m) - std::sqrt(n.dot(Ei * n))));
  }
  Mat4 expected;
  expected.topLeftCorner<3, 3>() = m * m.transpose() - Ei;
  expected.block<3, 1>(0, 3) = m;
  expected.block<1, 3>(3, 0) = m.transpose();
  expected(3, 3) = 1.0;
  Mat4 Q;
  // Fitted in a frame centred near m with unit size, mapped back.
  ASSERT_TRUE(fit_dual_quadric(planes, m + Vec3(0.1, -0.2, 0.05), std::sqrt(Ei.trace()), &Q));
  EXPECT_LT((normalised(Q) - normalised(expected)).norm(), 1e-8) << Q << "\n" << expected;
  for (const Vec4& q : planes) EXPECT_NEAR(q.dot(Q * q), 0.0, 1e-9 * Q.norm() * q.squaredNorm());
}

TEST(QuadricFit, SphereTangentPlanes) {
  check_ellipsoid(Mat3::Identity() / (0.7 * 0.7), Vec3(0.3, -1.2, 2.0), 1, 60);
  check_ellipsoid(Mat3::Identity() / (1e3 * 1e3), Vec3(1e4, 0, -1e4), 2, 60);
}

TEST(QuadricFit, EllipsoidTangentPlanes) {
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 axes(0.5, 1.3, 2.2);
  const Mat3 E = R * axes.cwiseInverse().cwiseAbs2().asDiagonal() * R.transpose();
  check_ellipsoid(E, Vec3(-0.4, 0.8, 0.1), 3, 80);
}

TEST(QuadricFit, RejectsEmptyInput) {
  Mat4 Q;
  EXPECT_FALSE(fit_dual_quadric(std::vector<Vec4>{}, &Q));
}

// Dense search of lambda(q(t)) on [0,1]: 20001 samples, then golden-section refinement around
// the best samples.
Vec2 dense_range(const Mat4& Qf, const Vec4& D, const Vec4& q0, const Vec4& q1) {
  auto lam = [&](double t) { return plane_lambda(Qf, D, (1 - t) * q0 + t * q1); };
  const int n = 20000;
  const auto [imin, imax] = extreme_indices(n + 1, [&](int i) { return lam(double(i) / n); });
  const double vmin = lam(double(imin) / n), vmax = lam(double(imax) / n);
  auto golden = [&](int i, double sign) {
    double a = std::max(0.0, (i - 1.0) / n), b = std::min(1.0, (i + 1.0) / n);
    const double r = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int it = 0; it < 200; ++it) {
      const double c = b - r * (b - a), d = a + r * (b - a);
      if (sign * lam(c) < sign * lam(d))
        b = d;
      else
        a = c;
    }
    return lam(0.5 * (a + b));
  };
  return Vec2(std::min(vmin, golden(imin, 1.0)), std::max(vmax, golden(imax, -1.0)));
}

TEST(QuadricOffsets, ClosedFormMatchesDenseSearch) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  int interior = 0, appendix_d = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Mat4 A;
    for (int i = 0; i < 16; ++i) A(i / 4, i % 4) = g(rng);
    const Mat4 Qf = A + A.transpose();
    const Vec4 D(g(rng), g(rng), g(rng), trial % 2 ? 0.0 : 1.0);
    // Planes with D.q > 0: draw, flip if needed.
    Vec4 q0(g(rng), g(rng), g(rng), g(rng)), q1(g(rng), g(rng), g(rng), g(rng));
    if (D.dot(q0) < 0) q0 = -q0;
    if (D.dot(q1) < 0) q1 = -q1;
    if (D.dot(q0) < 0.05 * D.norm() * q0.norm() || D.dot(q1) < 0.05 * D.norm() * q1.norm()) continue;
    const Vec2 closed = wedge_lambda_range(Qf, D, q0, q1);
    const Vec2 dense = dense_range(Qf, D, q0, q1);
    const double scale = std::max(std::abs(dense[0]), std::abs(dense[1]));
    EXPECT_NEAR(closed[0], dense[0], 1e-9 * scale) << trial;
    EXPECT_NEAR(closed[1], dense[1], 1e-9 * scale) << trial;
    const double l0 = plane_lambda(Qf, D, q0), l1 = plane_lambda(Qf, D, q1);
    const bool has_interior = closed[0] < std::min(l0, l1) || closed[1] > std::max(l0, l1);
    interior += has_interior;
    // Appendix D's lambda* is the same interior extremum.
    double ls;
    if (appendix_d_lambda_star(Qf, D, q0, q1, &ls)) {
      ++appendix_d;
      EXPECT_TRUE(std::abs(ls - closed[0]) <= 1e-8 * scale || std::abs(ls - closed[1]) <= 1e-8 * scale)
          << trial << " " << ls << " " << closed.transpose();
    }
  }
  EXPECT_GT(interior, 20);
  EXPECT_GT(appendix_d, 20);
}

}  // namespace
}  // namespace qsil::edgetree
