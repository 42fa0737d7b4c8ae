/// @file conic_test.cpp
/// Point on a conic [QSS Appendix C]: for random real conics (ellipses, hyperbolas, parabolas,
/// line pairs, a double point) a point on the conic is found, with |y^T C y| <= 1e-8 |C| |y|^2;
/// for empty conics (definite C) none is claimed. Convex point-in-polygon. Fixed seeds.

#include "edgetree/conic.h"

#include <gtest/gtest.h>

#include <random>

namespace qsil::edgetree {
namespace {

// Congruence by a random affine map: C' = T^T C T keeps the conic type.
Mat3 random_affine(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Mat3 T = Mat3::Identity();
  T.topLeftCorner<2, 2>() << g(rng), g(rng), g(rng), g(rng);
  T(0, 2) = 2 * g(rng);
  T(1, 2) = 2 * g(rng);
  return T;
}

TEST(RejectionConic, RealConicsHaveAPointFound) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(0.1, 3.0);
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Mat3 C0 = Mat3::Zero();
    switch (trial % 5) {
      case 0: C0.diagonal() << 1 / u(rng), 1 / u(rng), -1; break;  // ellipse
      case 1: C0.diagonal() << 1 / u(rng), -1 / u(rng), 1; break;  // hyperbola
      case 2:
        C0(0, 0) = 1;
        C0(1, 2) = C0(2, 1) = -0.5 * u(rng);
        break;  // parabola x^2 = a y
      case 3:
        C0(0, 0) = 1;
        C0(1, 1) = -u(rng);
        break;  // line pair
      case 4:
        C0(0, 0) = 1;
        C0(1, 1) = u(rng);
        break;  // single real point
    }
    const Mat3 T = random_affine(rng);
    if (std::abs(T.determinant()) < 1e-3) continue;
    const Mat3 C = T.transpose() * C0 * T;
    std::array<Vec2, 4> pts;
    const int n = find_conic_points(C, &pts);
    EXPECT_GT(n, 0) << "type " << trial % 5 << "\n" << C;
    for (int i = 0; i < n; ++i) {
      const double scale = C.cwiseAbs().maxCoeff() * (1 + pts[i].squaredNorm());
      EXPECT_LE(std::abs(conic_value(C, pts[i])), 1e-8 * scale) << trial;
    }
    ++checked;
  }
  EXPECT_GT(checked, 1500);
}

TEST(RejectionConic, EmptyConicsClaimNoPoint) {
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> u(0.1, 3.0);
  for (int trial = 0; trial < 2000; ++trial) {
    Mat3 C0 = Mat3::Zero();
    C0.diagonal() << u(rng), u(rng), u(rng);  // x^2/a + y^2/b + c = 0: no real point
    if (trial % 2) C0 = -C0;
    const Mat3 T = random_affine(rng);
    if (std::abs(T.determinant()) < 1e-3) continue;
    std::array<Vec2, 4> pts;
    EXPECT_EQ(find_conic_points(T.transpose() * C0 * T, &pts), 0) << trial;
  }
}

TEST(RejectionConic, PointInConvexPolygon) {
  const std::vector<Vec2> sq = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  EXPECT_TRUE(point_in_convex_polygon(sq, Vec2(0.5, 0.5)));
  EXPECT_TRUE(point_in_convex_polygon(sq, Vec2(1.0, 0.5)));  // on the boundary
  EXPECT_FALSE(point_in_convex_polygon(sq, Vec2(1.01, 0.5)));
  const std::vector<Vec2> cw(sq.rbegin(), sq.rend());
  EXPECT_TRUE(point_in_convex_polygon(cw, Vec2(0.2, 0.9)));
  EXPECT_FALSE(point_in_convex_polygon(cw, Vec2(-0.2, 0.9)));
  EXPECT_FALSE(point_in_convex_polygon(std::vector<Vec2>{Vec2(0, 0), Vec2(1, 1)}, Vec2(0.5, 0.5)));
}

}  // namespace
}  // namespace qsil::edgetree
