/// @file environment_light_test.cpp
/// Tests of the environment emitter (include/qsil/environment_light.h): the Mitsuba 3 `envmap`
/// uv convention, lookup, importance sampling (chi-square, normalisation, eval/pdf consistency)
/// on a small synthetic map and on scenes/stability/envmaps/sunset.exr (1024 x 512, a sun near the
/// horizon), and the constant / none cases.
///
/// Expected counts integrate pdf(direction) in solid angle with a midpoint rule of 2 x 2 (sunset)
/// or 4 x 4 (synthetic) points per texel in (theta, phi) of the map frame. The chi-square bins are
/// blocks of whole texels, computed from each sampled *direction* with this file's own copy of
/// the convention, so a wrong Jacobian or convention in the class shows up. Chi-square at a
/// family-wise significance of 1% over the 2 chi-square tests of this file (Šidák), pooling
/// expected < 5; Monte Carlo comparisons at 4.5 sigma.

#include "qsil/environment_light.h"

#include "qsil/error.h"
#include "qsil/image.h"

#include "chi2.h"
#include "env_map_images.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <vector>

namespace qsil {
namespace {

using test::TestRng;

const double kSignificance = test::sidak(0.01, 2);

// ---- the convention, written out independently of the class (Mitsuba 3 envmap.cpp)
Vec3 ref_uv_to_dir(double u, double v) { return test::envmap_direction(u, v); }
Vec2 ref_dir_to_uv(const Vec3& d) {
  double u = std::atan2(d.x(), -d.z()) / (2 * kPi);
  if (u < 0) u += 1;
  return {u, std::acos(std::clamp(d.y(), -1.0, 1.0)) / kPi};
}

/// A rotation about a tilted axis (so that no axis of the map frame is a world axis).
Mat3 some_rotation() { return Eigen::AngleAxisd(0.7, Vec3(0.3, 1.0, -0.4).normalized()).toRotationMatrix(); }

/// 16 x 8 synthetic map: a gradient, a row and scattered texels of zero, one very bright texel.
Environment synthetic_env() {
  Environment env;
  env.type = Environment::Type::EnvMap;
  env.scale = 1.5;
  env.to_world = some_rotation();
  env.texels = test::envmap_image(16, 8, [](int x, int y) {
    if (y == 3 || (x + y) % 5 == 0) return Color(0, 0, 0);
    if (x == 11 && y == 5) return Color(40, 30, 10);
    return Color(0.1 + 0.05 * x, 0.2 + 0.1 * y, 0.3);
  });
  return env;
}

Environment load_sunset() {
  Environment env;
  env.type = Environment::Type::EnvMap;
  env.filename = test::data_file("scenes/stability/envmaps/sunset.exr");
  env.texels = read_exr(env.filename);
  env.scale = 2.0;
  env.to_world = some_rotation();
  return env;
}

/// Per-texel integral of the light's pdf in solid angle (sub x sub midpoint points per texel in
/// (theta, phi)), accumulated into bu x bv blocks of texels. Returns the block integrals.
std::vector<double> block_integrals(const EnvironmentLight& light, const Mat3& to_world, int bu, int bv, int sub) {
  const int w = light.width(), h = light.height();
  std::vector<double> out(size_t(bu) * size_t(bv), 0.0);
  const double dv = 1.0 / (h * sub), du = 1.0 / (w * sub);
  for (int y = 0; y < h * sub; ++y) {
    const double v = (y + 0.5) * dv;
    const double weight = std::sin(kPi * v) * (kPi * dv) * (2 * kPi * du);
    const int by = int(int64_t(y / sub) * bv / h);
    for (int x = 0; x < w * sub; ++x) {
      const double u = (x + 0.5) * du;
      const double p = light.pdf(to_world * ref_uv_to_dir(u, v));
      out[size_t(by) * bu + size_t(int64_t(x / sub) * bu / w)] += p * weight;
    }
  }
  return out;
}

/// Histogram of n samples in bu x bv texel blocks, binned from the world direction.
std::vector<double> block_histogram(const EnvironmentLight& light, const Mat3& to_world, int bu, int bv, int n,
                                    uint64_t seed) {
  std::vector<double> obs(size_t(bu) * size_t(bv), 0.0);
  TestRng rng(seed);
  for (int i = 0; i < n; ++i) {
    const auto s = light.sample(rng.uniform2());
    if (!(s.pdf > 0)) continue;
    const Vec2 uv = ref_dir_to_uv(to_world.transpose() * s.dir);
    const int tx = std::min(int(uv.x() * light.width()), light.width() - 1);
    const int ty = std::min(int(uv.y() * light.height()), light.height() - 1);
    obs[size_t(ty * bv / light.height()) * bu + size_t(tx * bu / light.width())] += 1;
  }
  return obs;
}

// ---------------------------------------------------------------------------------------------
// Convention
// ---------------------------------------------------------------------------------------------

TEST(EnvironmentLightConvention, KnownDirectionsAndRoundTrip) {
  // Mitsuba 3: +y is the top row (v = 0), -z is u = 0, +x is u = 1/4, +z is u = 1/2, -x is 3/4.
  EXPECT_NEAR(EnvironmentLight::direction_to_uv(Vec3(0, 1, 0)).y(), 0.0, 1e-15);
  EXPECT_NEAR(EnvironmentLight::direction_to_uv(Vec3(0, -1, 0)).y(), 1.0, 1e-15);
  EXPECT_NEAR(EnvironmentLight::direction_to_uv(Vec3(0, 0, -1)).x(), 0.0, 1e-15);
  EXPECT_NEAR(EnvironmentLight::direction_to_uv(Vec3(1, 0, 0)).x(), 0.25, 1e-15);
  EXPECT_NEAR(EnvironmentLight::direction_to_uv(Vec3(0, 0, 1)).x(), 0.5, 1e-15);
  EXPECT_NEAR(EnvironmentLight::direction_to_uv(Vec3(-1, 0, 0)).x(), 0.75, 1e-15);
  EXPECT_NEAR(EnvironmentLight::direction_to_uv(Vec3(0, 0, 1)).y(), 0.5, 1e-15);
  TestRng rng(41);
  for (int i = 0; i < 10000; ++i) {
    const Vec3 d = square_to_uniform_sphere(rng.uniform2());
    const Vec2 uv = EnvironmentLight::direction_to_uv(d);
    ASSERT_TRUE(uv.x() >= 0 && uv.x() < 1 && uv.y() >= 0 && uv.y() <= 1);
    ASSERT_LT((EnvironmentLight::uv_to_direction(uv) - d).norm(), 1e-12);
    ASSERT_LT((ref_uv_to_dir(uv.x(), uv.y()) - d).norm(), 1e-12);
    const Vec2 uv2 = rng.uniform2();
    ASSERT_LT((EnvironmentLight::direction_to_uv(EnvironmentLight::uv_to_direction(uv2)) - uv2).norm(), 1e-9);
  }
}

TEST(EnvironmentLightConvention, LookupIsNearestTexelTimesScale) {
  const Environment env = synthetic_env();
  const EnvironmentLight light(env);
  ASSERT_TRUE(light.present());
  const int r = env.texels.channel_index("R"), g = env.texels.channel_index("G"), b = env.texels.channel_index("B");
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x)
      for (double fx : {0.05, 0.5, 0.95})
        for (double fy : {0.05, 0.5, 0.95}) {
          const Vec3 d = env.to_world * ref_uv_to_dir((x + fx) / 16, (y + fy) / 8);
          const Color c = light.eval(d);
          ASSERT_NEAR(c[0], 1.5 * env.texels.at(r, x, y), 1e-6) << x << " " << y;
          ASSERT_NEAR(c[1], 1.5 * env.texels.at(g, x, y), 1e-6);
          ASSERT_NEAR(c[2], 1.5 * env.texels.at(b, x, y), 1e-6);
        }
}

// ---------------------------------------------------------------------------------------------
// Sampling
// ---------------------------------------------------------------------------------------------

/// The checks shared by the synthetic map and sunset: normalisation, chi-square over texel
/// blocks, sample/pdf/eval agreement, E[L/pdf] = 4 pi average, zero texels never sampled.
void check_env_sampling(const Environment& env, int bu, int bv, int sub, int n, uint64_t seed) {
  const EnvironmentLight light(env);
  const std::vector<double> integrals = block_integrals(light, env.to_world, bu, bv, sub);
  double total = 0;
  for (double x : integrals) total += x;
  // The midpoint rule is exact for the constant pdf_uv per texel up to O(1/(H sub)^2).
  EXPECT_NEAR(total, 1.0, 1e-4) << "pdf integral over the sphere";

  std::vector<double> expected(integrals.size());
  for (size_t i = 0; i < integrals.size(); ++i) expected[i] = integrals[i] * n;
  const auto r = test::chi2_test(block_histogram(light, env.to_world, bu, bv, n, seed), expected, kSignificance);
  EXPECT_TRUE(r.passed) << r.message;
  testing::Test::RecordProperty("chi2", r.message);

  // Sample consistency and the estimator of the integral of the radiance.
  TestRng rng(seed + 1);
  const int m = 100000;
  Eigen::Array3d sum = Eigen::Array3d::Zero(), sum2 = Eigen::Array3d::Zero();
  for (int i = 0; i < m; ++i) {
    const auto s = light.sample(rng.uniform2());
    ASSERT_GT(s.pdf, 0);
    ASSERT_NEAR(s.dir.norm(), 1.0, 1e-12);
    ASSERT_NEAR(light.pdf(s.dir), s.pdf, 1e-9 * s.pdf);
    ASSERT_GT(s.radiance.maxCoeff(), 0.0) << "a black texel was sampled";
    const Color e = light.eval(s.dir);
    ASSERT_LT((e - s.radiance).abs().maxCoeff(), 1e-9 * s.radiance.maxCoeff());
    const Eigen::Array3d w = s.radiance / s.pdf;
    sum += w;
    sum2 += w * w;
  }
  const Eigen::Array3d mean = sum / m, sigma = ((sum2 / m - mean * mean).max(0.0) / m).sqrt();
  const Eigen::Array3d target = 4 * kPi * light.average_radiance();
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(mean[k], target[k], 4.5 * sigma[k] + 1e-9 * target[k]) << "channel " << k;
}

TEST(EnvironmentLightSampling, SyntheticMap) {
  const Environment env = synthetic_env();
  // Blocks of single texels: 16 x 8 bins, 10^6 samples.
  check_env_sampling(env, 16, 8, 4, 1000000, 51);
  // average_radiance is the solid-angle mean of the texels.
  const EnvironmentLight light(env);
  Color avg = Color::Zero();
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x) {
      const Vec3 d = env.to_world * ref_uv_to_dir((x + 0.5) / 16, (y + 0.5) / 8);
      const double solid_angle = (2 * kPi / 16) * (std::cos(kPi * y / 8) - std::cos(kPi * (y + 1) / 8));
      avg += light.eval(d) * solid_angle;
    }
  avg /= 4 * kPi;
  EXPECT_LT((avg - light.average_radiance()).abs().maxCoeff(), 1e-12 * avg.maxCoeff());
}

TEST(EnvironmentLightSampling, SunsetExr) {
  const Environment env = load_sunset();
  ASSERT_EQ(env.texels.width, 1024);
  ASSERT_EQ(env.texels.height, 512);
  // Blocks of 16 x 16 texels: 64 x 32 bins, 10^6 samples.
  check_env_sampling(env, 64, 32, 2, 1000000, 61);
}

TEST(EnvironmentLightSampling, Chi2RejectsFivePercentPdfTilt) {
  // Negative control: a density tilted by 5% toward +y of the map (renormalised) is rejected.
  const Environment env = synthetic_env();
  const EnvironmentLight light(env);
  std::vector<double> integrals(16 * 8, 0.0);
  double total = 0;
  for (int y = 0; y < 8 * 4; ++y)
    for (int x = 0; x < 16 * 4; ++x) {
      const double u = (x + 0.5) / 64, v = (y + 0.5) / 32;
      const Vec3 dl = ref_uv_to_dir(u, v);
      const double p =
          light.pdf(env.to_world * dl) * (1 + 0.05 * dl.y()) * std::sin(kPi * v) * (kPi / 32) * (2 * kPi / 64);
      integrals[size_t(y / 4) * 16 + size_t(x / 4)] += p;
      total += p;
    }
  for (double& e : integrals) e *= 1000000 / total;
  const auto r = test::chi2_test(block_histogram(light, env.to_world, 16, 8, 1000000, 71), integrals, kSignificance);
  EXPECT_FALSE(r.passed) << r.message;
}

// ---------------------------------------------------------------------------------------------
// Constant, none, black, invalid input
// ---------------------------------------------------------------------------------------------

TEST(EnvironmentLightKinds, ConstantNoneAndBlack) {
  Environment none;
  const EnvironmentLight n(none);
  EXPECT_FALSE(n.present());
  EXPECT_TRUE((n.eval(Vec3(0, 0, 1)) == 0).all());
  EXPECT_EQ(n.sample(Vec2(0.3, 0.3)).pdf, 0.0);
  EXPECT_EQ(n.pdf(Vec3(0, 0, 1)), 0.0);
  EXPECT_TRUE((n.average_radiance() == 0).all());

  Environment constant;
  constant.type = Environment::Type::Constant;
  constant.radiance = Color(0.2, 0.4, 0.8);
  const EnvironmentLight c(constant);
  EXPECT_TRUE(c.present());
  TestRng rng(81);
  for (int i = 0; i < 100; ++i) {
    const auto s = c.sample(rng.uniform2());
    EXPECT_NEAR(s.pdf, 1 / (4 * kPi), 1e-15);
    EXPECT_NEAR(c.pdf(s.dir), 1 / (4 * kPi), 1e-15);
    EXPECT_TRUE((s.radiance == constant.radiance).all());
    EXPECT_TRUE((c.eval(s.dir) == constant.radiance).all());
  }
  EXPECT_TRUE((c.average_radiance() == constant.radiance).all());

  Environment black = synthetic_env();
  black.texels = test::envmap_image(8, 4, [](int, int) { return Color(0, 0, 0); });
  const EnvironmentLight b(black);
  EXPECT_TRUE(b.present());
  EXPECT_EQ(b.sample(Vec2(0.5, 0.5)).pdf, 0.0);  // nothing to sample
  EXPECT_EQ(b.pdf(Vec3(0, 1, 0)), 0.0);
}

TEST(EnvironmentLightKinds, RejectsBadInput) {
  Environment env = synthetic_env();
  env.to_world = 2.0 * Mat3::Identity();
  EXPECT_THROW(EnvironmentLight{env}, Error);
  env = synthetic_env();
  env.texels.channel_names = {"X", "Y", "Z"};
  EXPECT_THROW(EnvironmentLight{env}, Error);
  env = synthetic_env();
  env.texels.at(0, 1, 1) = std::nanf("");
  EXPECT_THROW(EnvironmentLight{env}, Error);
}

}  // namespace
}  // namespace qsil
