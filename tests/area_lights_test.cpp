/// @file area_lights_test.cpp
/// Tests of area-emitter sampling (include/qsil/area_lights.h): uniform density over the union of
/// emitting triangles (chi-square over a grid of a rectangle light, area via 1/pdf_area), the
/// solid-angle conversion against the analytic solid angle of a square, one-sided emission, and
/// zero-area triangles. Monte Carlo comparisons at 4.5 sigma (two-sided 7e-6 each); chi-square at
/// 1% significance with pooling of expected < 5.

#include "qsil/area_lights.h"

#include "chi2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace qsil {
namespace {

using test::TestRng;

/// Rectangle [-sx, sx] x [-sy, sy] in the plane z = z0 as two triangles, normal +z or -z.
Shape rectangle(double sx, double sy, double z0, bool up, const Color& radiance, bool emitter = true) {
  Shape s;
  s.type = "rectangle";
  s.is_emitter = emitter;
  s.radiance = radiance;
  s.mesh.positions = {Vec3(-sx, -sy, z0), Vec3(sx, -sy, z0), Vec3(sx, sy, z0), Vec3(-sx, sy, z0)};
  if (up)
    s.mesh.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  else
    s.mesh.triangles = {Eigen::Vector3i(0, 2, 1), Eigen::Vector3i(0, 3, 2)};
  return s;
}

TEST(AreaLights, UniformOverUnionOfEmitters) {
  // Two emitters (areas 4 x 2 = 8 and 2 x 2 = 4) and a non-emitter: pdf_area = 1/12, each shape
  // chosen in proportion to its area, points uniform (chi-square over a 12 x 6 grid on shape 0).
  Scene scene;
  scene.shapes.push_back(rectangle(2, 1, 0, true, Color(1, 1, 1)));
  scene.shapes.push_back(rectangle(5, 5, -1, true, Color(1, 1, 1), false));
  scene.shapes.push_back(rectangle(1, 1, 3, false, Color(2, 2, 2)));
  const AreaLights lights(scene);
  ASSERT_FALSE(lights.empty());
  EXPECT_NEAR(lights.total_area(), 12.0, 1e-12);
  EXPECT_NEAR(lights.pdf_area(), 1.0 / 12, 1e-15);

  const int n = 600000, gx = 12, gy = 6;
  std::vector<double> obs(gx * gy, 0.0);
  int count[3] = {0, 0, 0};
  TestRng rng(91);
  double inv_pdf_sum = 0;
  for (int i = 0; i < n; ++i) {
    const auto s = lights.sample(rng.uniform2(), rng.uniform());
    ASSERT_TRUE(s.shape == 0 || s.shape == 2);
    ASSERT_TRUE(s.triangle == 0 || s.triangle == 1);
    ASSERT_EQ(s.pdf_area, lights.pdf_area());
    inv_pdf_sum += 1 / s.pdf_area;
    ++count[s.shape];
    if (s.shape == 0) {
      ASSERT_NEAR(s.point.z(), 0.0, 1e-15);
      ASSERT_EQ(s.normal, Vec3(0, 0, 1));
      const int ix = std::clamp(int((s.point.x() + 2) / 4 * gx), 0, gx - 1);
      const int iy = std::clamp(int((s.point.y() + 1) / 2 * gy), 0, gy - 1);
      obs[size_t(iy * gx + ix)] += 1;
    } else {
      ASSERT_EQ(s.normal, Vec3(0, 0, -1));
      ASSERT_LE(std::abs(s.point.x()), 1.0 + 1e-15);
    }
  }
  // The area estimate via 1/pdf_area is exact (the density is constant).
  EXPECT_NEAR(inv_pdf_sum / n, 12.0, 1e-9);
  // Shape choice: binomial with p = 8/12.
  const double p = 8.0 / 12, sd = std::sqrt(n * p * (1 - p));
  EXPECT_NEAR(count[0], n * p, 4.5 * sd);
  // Uniformity on shape 0: every cell expects count[0] / (gx gy).
  const std::vector<double> exp(size_t(gx * gy), double(count[0]) / (gx * gy));
  const auto r = test::chi2_test(obs, exp, 0.01);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(AreaLights, RectangleAreaByMonteCarloOfTheIndicator) {
  // Estimate the area of a sub-rectangle [0,1] x [-1,1] of a 4 x 2 light from the samples:
  // area = E[1{x in R} / pdf_area]; analytic 2.
  Scene scene;
  scene.shapes.push_back(rectangle(2, 1, 0, true, Color(1, 1, 1)));
  const AreaLights lights(scene);
  TestRng rng(92);
  const int n = 400000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const auto s = lights.sample(rng.uniform2(), rng.uniform());
    const double w = (s.point.x() >= 0 && s.point.x() <= 1) ? 1 / s.pdf_area : 0;
    sum += w;
    sum2 += w * w;
  }
  const double mean = sum / n, sigma = std::sqrt((sum2 / n - mean * mean) / n);
  EXPECT_NEAR(mean, 2.0, 4.5 * sigma);
}

TEST(AreaLights, SolidAngleOfSquareMatchesAnalytic) {
  // A square of side a at distance d, seen from a point on its axis (and from an off-axis point
  // against the analytic rectangle formula): E[1 / pdf_omega] over light samples = solid angle.
  const double a = 0.5;
  for (double d : {0.3, 2.0, 10.0}) {
    Scene scene;
    scene.shapes.push_back(rectangle(a / 2, a / 2, 0, false, Color(1, 1, 1)));  // faces -z
    const AreaLights lights(scene);
    const Vec3 from(0, 0, -d);
    // Solid angle of an a x b rectangle seen on axis at distance d:
    // 4 asin(a b / sqrt((a^2 + 4 d^2)(b^2 + 4 d^2))).
    const double omega = 4 * std::asin(a * a / std::sqrt((a * a + 4 * d * d) * (a * a + 4 * d * d)));
    TestRng rng(93);
    const int n = 200000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
      const auto s = lights.sample(rng.uniform2(), rng.uniform());
      const double pdf = AreaLights::to_solid_angle(s.pdf_area, from, s.point, s.normal);
      ASSERT_GT(pdf, 0);
      sum += 1 / pdf;
      sum2 += 1 / (pdf * pdf);
    }
    const double mean = sum / n, sigma = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, omega, 4.5 * sigma + 1e-12 * omega) << "d = " << d;
    // The small-square limit: pdf_omega -> pdf_area d^2 at the centre.
    EXPECT_NEAR(AreaLights::to_solid_angle(1.0 / (a * a), from, Vec3(0, 0, 0), Vec3(0, 0, -1)), d * d / (a * a), 1e-12);
  }
  // Oblique: the cosine at the light. From (0, 1, -1) the centre is at 45 degrees: pdf = p d^2 / cos.
  EXPECT_NEAR(AreaLights::to_solid_angle(2.0, Vec3(0, 1, -1), Vec3(0, 0, 0), Vec3(0, 0, -1)),
              2.0 * 2.0 / std::sqrt(0.5), 1e-12);
  // Degenerate: edge-on or coincident -> 0 (invalid).
  EXPECT_EQ(AreaLights::to_solid_angle(1.0, Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 1)), 0.0);
  EXPECT_EQ(AreaLights::to_solid_angle(1.0, Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 1)), 0.0);
}

TEST(AreaLights, OneSidedRadianceAndEmptyScenes) {
  Scene scene;
  scene.shapes.push_back(rectangle(1, 1, 0, true, Color(1, 2, 3), false));
  scene.shapes.push_back(rectangle(1, 1, 0, true, Color(1, 2, 3)));
  const AreaLights lights(scene);
  const Vec3 n(0, 0, 1);
  EXPECT_TRUE((lights.radiance(1, n, Vec3(0.3, 0, 0.9).normalized()) == Color(1, 2, 3)).all());
  EXPECT_TRUE((lights.radiance(1, n, Vec3(0.3, 0, -0.9).normalized()) == 0).all());  // back side
  EXPECT_TRUE((lights.radiance(0, n, Vec3(0, 0, 1)) == 0).all());                    // not an emitter
  EXPECT_TRUE((lights.radiance(5, n, Vec3(0, 0, 1)) == 0).all());                    // no such shape

  Scene none;
  none.shapes.push_back(rectangle(1, 1, 0, true, Color(1, 1, 1), false));
  const AreaLights empty(none);
  EXPECT_TRUE(empty.empty());
  EXPECT_EQ(empty.pdf_area(), 0.0);
  EXPECT_EQ(empty.sample(Vec2(0.5, 0.5), 0.5).pdf_area, 0.0);

  // A zero-area triangle between two real ones is never sampled.
  Scene degenerate;
  Shape s = rectangle(1, 1, 0, true, Color(1, 1, 1));
  s.mesh.positions.push_back(Vec3(5, 5, 0));
  s.mesh.triangles.insert(s.mesh.triangles.begin() + 1, Eigen::Vector3i(4, 4, 0));
  degenerate.shapes.push_back(s);
  const AreaLights dl(degenerate);
  EXPECT_NEAR(dl.total_area(), 4.0, 1e-12);
  TestRng rng(94);
  for (int i = 0; i < 10000; ++i) ASSERT_NE(dl.sample(rng.uniform2(), rng.uniform()).triangle, 1);
  for (double u : {0.0, 0.5, std::nextafter(0.5, 0.0), std::nextafter(1.0, 0.0)})
    ASSERT_NE(dl.sample(Vec2(0.3, 0.3), u).triangle, 1);
}

}  // namespace
}  // namespace qsil
