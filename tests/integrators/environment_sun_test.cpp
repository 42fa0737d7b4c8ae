/// @file environment_sun_test.cpp
/// Tests of the environment map's sun (include/qsil/environment_sun.h) and of the light sphere
/// that stands for it in the light-aware importance (sun_light_sphere, integrators/boundary_setup.h):
/// - a disc of bright texels in a dim sky is found: its axis is the disc's, in the world frame
///   (the map is rotated), its cone holds the centre of every disc texel, it is not much wider
///   than the disc, and its share and radiance are the brute-force sums over the texels;
/// - a broad glow, a large softbox, a flat sky and a sun too small for its sky are not suns, and
///   the same sun in a darker sky is (the arc criterion, kSunMinArcRatio, on both sides);
/// - the suns of scenes/stability/envmaps/sunset.exr (small, near the horizon), sunrise.exr and
///   city.exr are found, and the bundled maps without one (forest, courtyard, the studio of the
///   tests) have none;
/// - from every point of the scene's box, every direction of the sun's cone meets the light sphere
///   (the oracle: the ray's distance to the centre), and a sphere without the box's half diagonal
///   in its radius fails that (the test has power).
/// Random cases from fixed seeds.

#include "qsil/environment_sun.h"
#include "integrators/boundary_setup.h"
#include "qsil/image.h"

#include "chi2.h"
#include "env_map_images.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

namespace qsil {
namespace {

using test::TestRng;

/// The map-frame direction of the centre of texel (x, y) of a w x h map.
Vec3 texel_direction(int x, int y, int w, int h) { return test::envmap_direction((x + 0.5) / w, (y + 0.5) / h); }

/// A rotation about a tilted axis, so that no axis of the map frame is a world axis.
Mat3 some_rotation() { return Eigen::AngleAxisd(0.9, Vec3(-0.2, 1.0, 0.5).normalized()).toRotationMatrix(); }

/// A w x h map with radiance texel(x, y) (grey), rotated by some_rotation.
Environment make_map(int w, int h, const std::function<double(int, int)>& texel) {
  Environment env;
  env.type = Environment::Type::EnvMap;
  env.to_world = some_rotation();
  env.texels = test::envmap_image(w, h, [&](int x, int y) { return Color::Constant(texel(x, y)); });
  return env;
}

/// A map of a disc of radiance `sun` and angular radius `radius` (texel centres within it) about
/// map direction `axis`, in a sky of radiance `sky`.
Environment disc_map(int w, int h, const Vec3& axis, double radius, double sun, double sky) {
  return make_map(w, h,
                  [&](int x, int y) { return texel_direction(x, y, w, h).dot(axis) >= std::cos(radius) ? sun : sky; });
}

constexpr double kDegree = kPi / 180.0;

TEST(EnvironmentSun, FindsADiscOfBrightTexels) {
  const int w = 512, h = 256;
  const double texel = kPi / h;  // a texel's height in angle
  for (const Vec3& axis : {Vec3(0.3, 0.2, -0.9).normalized(), Vec3(-0.8, 0.55, 0.1).normalized()}) {
    const double radius = 2.0 * kDegree;
    const Environment env = disc_map(w, h, axis, radius, 500.0, 0.5);
    const EnvironmentLight light(env);
    const std::optional<EnvironmentSun> sun = find_environment_sun(light);
    ASSERT_TRUE(sun.has_value());
    // The axis: the centre of a disc texel, so within the disc's radius of the disc's axis.
    EXPECT_LE(std::acos(std::min(1.0, sun->axis.dot(env.to_world * axis))), radius);
    // The cone holds every disc texel's centre, and is at most the disc's diameter plus a texel
    // wider than the disc.
    double power = 0, cone_power = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Vec3 d = env.to_world * texel_direction(x, y, w, h);
        const double omega = (2 * kPi / w) * (std::cos(kPi * y / h) - std::cos(kPi * (y + 1) / h));
        const double l = env.texels.at(0, x, y);
        power += l * omega;
        if (d.dot(sun->axis) >= std::cos(sun->half_angle)) cone_power += l * omega;
        if (texel_direction(x, y, w, h).dot(axis) >= std::cos(radius)) {
          EXPECT_LE(std::acos(std::min(1.0, d.dot(sun->axis))), sun->half_angle);
        }
      }
    EXPECT_LE(sun->half_angle, 2 * radius + 2 * texel);
    EXPECT_GE(sun->half_angle, radius);
    EXPECT_NEAR(sun->share, cone_power / power, 1e-9);
    EXPECT_NEAR(sun->radiance, cone_power / (2 * kPi * (1 - std::cos(sun->half_angle))), 1e-9 * sun->radiance);
  }
}

TEST(EnvironmentSun, NoSunInABroadGlowASoftboxOrAFlatSky) {
  const int w = 256, h = 128;
  const Vec3 axis = Vec3(0.1, 0.6, -0.8).normalized();
  // A glow: radiance falling off over 30 degrees, its texels above 1 % of the brightest's far
  // beyond kSunMaxHalfAngle.
  const Environment glow = make_map(w, h, [&](int x, int y) {
    const double a = std::acos(std::min(1.0, texel_direction(x, y, w, h).dot(axis)));
    return 0.1 + 1000.0 * std::exp(-a / (30 * kDegree));
  });
  EXPECT_FALSE(find_environment_sun(EnvironmentLight(glow)).has_value());
  // A softbox of 15 degrees, as bright as a sun.
  EXPECT_FALSE(find_environment_sun(EnvironmentLight(disc_map(w, h, axis, 15 * kDegree, 1000.0, 0.1))).has_value());
  // A flat sky.
  EXPECT_FALSE(find_environment_sun(EnvironmentLight(make_map(w, h, [](int, int) { return 2.0; }))).has_value());
  // The same disc as a softbox of 5 degrees is a sun: the two above fail by their size alone.
  EXPECT_TRUE(find_environment_sun(EnvironmentLight(disc_map(w, h, axis, 5 * kDegree, 1000.0, 0.1))).has_value());
}

TEST(EnvironmentSun, ASmallSunCountsWhereItOutweighsItsSky) {
  // A sun of 0.5 degrees (texels of 0.35 degrees): an arc through it gathers about 100 x 2 x
  // (0.5 + 0.25) degrees = 2.6 (radiance x radians); half a great circle of a sky of 0.9 gathers
  // 2.8, of a sky of 0.3, 0.94. The sky stays below 1 % of the sun, so only the arc decides.
  const int w = 1024, h = 512;
  const Vec3 axis = Vec3(0.5, 0.1, 0.86).normalized();
  EXPECT_FALSE(find_environment_sun(EnvironmentLight(disc_map(w, h, axis, 0.5 * kDegree, 100.0, 0.9))).has_value());
  EXPECT_TRUE(find_environment_sun(EnvironmentLight(disc_map(w, h, axis, 0.5 * kDegree, 100.0, 0.3))).has_value());
}

/// A bundled map, scale 1, map frame = world.
Environment bundled_map(const std::string& path) {
  Environment env;
  env.type = Environment::Type::EnvMap;
  env.filename = test::data_file(path);
  env.texels = read_exr(env.filename);
  return env;
}

TEST(EnvironmentSun, TheBundledMaps) {
  const std::optional<EnvironmentSun> sun =
      find_environment_sun(EnvironmentLight(bundled_map("scenes/stability/envmaps/sunset.exr")));
  ASSERT_TRUE(sun.has_value());
  EXPECT_LT(sun->half_angle, 2 * kDegree);
  EXPECT_LT(std::abs(sun->axis.y()), std::sin(10 * kDegree));  // a low sun
  // Two clear skies with a sun (scenes/sun/): sunrise's holds most of the power, city's a quarter.
  for (const auto& [path, min_share] : {std::pair<const char*, double>{"scenes/stability/envmaps/sunrise.exr", 0.5},
                                        {"scenes/stability/envmaps/city.exr", 0.2}}) {
    const std::optional<EnvironmentSun> s = find_environment_sun(EnvironmentLight(bundled_map(path)));
    ASSERT_TRUE(s.has_value()) << path;
    EXPECT_LT(s->half_angle, 2 * kDegree) << path;
    EXPECT_GT(s->share, min_share) << path;
  }
  for (const char* path :
       {"scenes/envmaps/forest.exr", "scenes/envmaps/courtyard.exr", "tests/data/envmaps/studio.exr"})
    EXPECT_FALSE(find_environment_sun(EnvironmentLight(bundled_map(path))).has_value()) << path;
}

TEST(EnvironmentSun, NoneWithoutAMap) {
  Environment constant;
  constant.type = Environment::Type::Constant;
  constant.radiance = Color(1, 1, 1);
  EXPECT_FALSE(find_environment_sun(EnvironmentLight(constant)).has_value());
  EXPECT_FALSE(find_environment_sun(EnvironmentLight(Environment{})).has_value());
  EXPECT_FALSE(find_environment_sun(EnvironmentLight(make_map(8, 4, [](int, int) { return 0.0; }))).has_value());
}

/// The largest angle, over random points p of `box` and random directions w within the sun's cone,
/// by which the ray p + s w (s > 0) misses `sphere`: max over cases of (its distance to the centre
/// - radius) / radius, <= 0 where every ray meets the sphere ahead of p.
double worst_miss(const EnvironmentSun& sun, const Box3& box, const edgetree::LightSphere& sphere, TestRng& rng) {
  const Vec3 s = sun.axis.unitOrthogonal(), t = sun.axis.cross(s);
  double worst = -kInf;
  for (int i = 0; i < 20000; ++i) {
    Vec3 p;
    for (int k = 0; k < 3; ++k)
      p[k] = box.lo[k] + (box.hi[k] - box.lo[k]) * (i % 4 == 0 ? std::round(rng.uniform()) : rng.uniform());
    // A direction within the cone, a quarter of them on its rim.
    const double cos_a = i % 4 == 1 ? std::cos(sun.half_angle) : 1 - rng.uniform() * (1 - std::cos(sun.half_angle));
    const double phi = 2 * kPi * rng.uniform(), sin_a = std::sqrt(1 - cos_a * cos_a);
    const Vec3 w = cos_a * sun.axis + sin_a * (std::cos(phi) * s + std::sin(phi) * t);
    const Vec3 to_c = sphere.centre - p;
    const double along = to_c.dot(w);
    EXPECT_GT(along, 0);  // the sphere lies ahead of p
    const double dist = (to_c - along * w).norm();
    worst = std::max(worst, (dist - sphere.radius) / sphere.radius);
  }
  return worst;
}

TEST(EnvironmentSun, ItsLightSphereMeetsEveryDirectionOfTheConeFromTheWholeScene) {
  TestRng rng(91);
  for (int c = 0; c < 6; ++c) {
    EnvironmentSun sun;
    const double z = 2 * rng.uniform() - 1, phi = 2 * kPi * rng.uniform();
    sun.axis = Vec3(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
    sun.half_angle = c < 3 ? 0.3 * kDegree : 8 * kDegree;
    sun.radiance = 100;
    Box3 box;
    box.expand(Vec3(-3 + rng.uniform(), 0.5 * rng.uniform(), 100 + rng.uniform()));
    box.expand(Vec3(2 + 4 * rng.uniform(), 1 + 3 * rng.uniform(), 103 + rng.uniform()));
    edgetree::LightSphere sphere;
    ASSERT_TRUE(sun_light_sphere(sun, box, sphere));
    EXPECT_EQ(sphere.shape, -1);
    EXPECT_EQ(sphere.weight, sun.radiance);
    EXPECT_LE(worst_miss(sun, box, sphere, rng), 0.0) << "case " << c;
    // Power: without the box's half diagonal in its radius, rays from the box's corners miss.
    edgetree::LightSphere tight = sphere;
    tight.radius -= 0.5 * box.diagonal();
    EXPECT_GT(worst_miss(sun, box, tight, rng), 0.0) << "case " << c;
  }
  EnvironmentSun sun;
  sun.half_angle = 0.01;
  edgetree::LightSphere sphere;
  EXPECT_FALSE(sun_light_sphere(sun, Box3{}, sphere));  // an empty box
}

}  // namespace
}  // namespace qsil
