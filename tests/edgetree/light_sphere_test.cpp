/// @file light_sphere_test.cpp
/// Tests of the light spheres of silhouette_sampler.h (mesh emitters in the light-aware
/// importance, [QSS 3.6] extended beyond quad lights):
/// - light_billboard's quad stands in for the whole sphere: every ray from p toward a point of
///   the sphere passes through it (oracle: ray-quad intersection of tests/ray_hits.h, independent
///   of the library's geometry), it faces p, and there is none from inside the sphere;
/// - the importances see the light: an edge in front of a sphere light, in a scene with no
///   environment, gets a light-aware weight (EdgeMixture::total) equal to the one it gets from the
///   billboard given as a quad light, and none without the light;
/// - enclosing_light_weight counts exactly the spheres that hold p;
/// - light_core's cone, where a sphere light is the only light, holds the whole sphere.
/// Random cases from fixed seeds.

#include "qsil/edgetree/light_core.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "edgetree/edge_mixture.h"

#include "chi2.h"
#include "ray_hits.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace qsil::edgetree {
namespace {

using test::TestRng;

/// A uniformly distributed unit vector.
Vec3 unit_vector(TestRng& rng) {
  const double z = 2.0 * rng.uniform() - 1.0, phi = 2.0 * kPi * rng.uniform();
  const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {s * std::cos(phi), s * std::sin(phi), z};
}

TEST(LightSphere, BillboardHoldsEveryRayTowardTheSphere) {
  TestRng rng(71);
  int cases = 0;
  for (int c = 0; c < 400; ++c) {
    LightSphere light;
    light.centre = Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 10.0;
    light.radius = 0.01 + rng.uniform();
    light.weight = 1.0;
    light.shape = 3;
    // Distances from just outside the sphere (where the quad is largest) to 100 radii.
    const double d = light.radius * (1.0 + std::pow(10.0, -4.0 + 6.0 * rng.uniform()));
    const Vec3 p = light.centre + unit_vector(rng) * d;
    LightPolygon quad;
    ASSERT_TRUE(light_billboard(light, p, quad)) << "p outside the sphere at " << d / light.radius << " radii";
    EXPECT_EQ(quad.shape, 3);
    EXPECT_EQ(quad.weight, 1.0);
    EXPECT_GT(quad.normal.dot(p - quad.corners[0]), 0.0) << "the emitting side faces p";
    std::array<Vec3, 4> rel;
    for (int i = 0; i < 4; ++i) rel[size_t(i)] = quad.corners[size_t(i)] - p;
    // Points of the sphere that p sees, and the tangent points (the hardest), through the quad.
    for (int k = 0; k < 200; ++k) {
      const Vec3 x = light.centre + unit_vector(rng) * light.radius * (1.0 - 1e-9);
      EXPECT_TRUE(test::ray_hits_quad(x - p, rel)) << "case " << c << ": a ray toward the sphere misses the quad";
    }
    ++cases;
  }
  EXPECT_EQ(cases, 400);
}

TEST(LightSphere, NoBillboardFromInside) {
  LightSphere light{Vec3(1, 2, 3), 0.5, 2.0, 0};
  LightPolygon quad;
  EXPECT_FALSE(light_billboard(light, Vec3(1, 2, 3.2), quad));
  EXPECT_FALSE(light_billboard(light, Vec3(1, 2, 3.5), quad));  // on the sphere
  EXPECT_TRUE(light_billboard(light, Vec3(1, 2, 3.5 + 1e-9), quad));
  light.weight = 0;
  EXPECT_FALSE(light_billboard(light, Vec3(1, 2, 10), quad)) << "a light without radiance gives no quad";
}

TEST(LightSphere, EnclosingWeightCountsTheSpheresThatHoldP) {
  const std::vector<LightSphere> spheres{{Vec3(0, 0, 0), 1.0, 2.0, 0}, {Vec3(0.5, 0, 0), 1.0, 3.0, 1},
                                         {Vec3(5, 0, 0), 1.0, 7.0, 2}};
  EXPECT_EQ(enclosing_light_weight(&spheres, Vec3(0.2, 0, 0)), 5.0);
  EXPECT_EQ(enclosing_light_weight(&spheres, Vec3(-0.9, 0, 0)), 2.0);
  EXPECT_EQ(enclosing_light_weight(&spheres, Vec3(3, 0, 0)), 0.0);
  EXPECT_EQ(enclosing_light_weight(nullptr, Vec3(0, 0, 0)), 0.0);
}

/// p at the origin with shading normal +z and the diffuse LTC, no environment; an edge at height 2
/// across the direction of a sphere light at height 3 (radius 0.4, centred over (-0.9, 0.2)).
struct SphereLitEdge {
  SilhouetteQuery q;
  Edge e;
  std::vector<LightSphere> spheres{{Vec3(-0.9, 0.2, 3.0), 0.4, 50.0, 2}};
  std::vector<double> emission{0.0, 0.0, 50.0};
  SphereLitEdge() {
    q.p = Vec3::Zero();
    q.frame = Frame(Vec3::UnitZ());
    q.ltc = ltc_diffuse();
    q.env_weight = 0.0;
    e.p0 = Vec3(-2.5, -1.5, 2.0);
    e.p1 = Vec3(0.5, 2.0, 2.0);
    e.length = (e.p1 - e.p0).norm();
    e.shape = 1;
    q.emission = &emission;
  }
};

TEST(LightSphere, EdgeInFrontOfTheLightGetsItsWeight) {
  SphereLitEdge s;
  std::vector<LocalLight> local;
  local_lights(s.q, local);
  EXPECT_TRUE(local.empty());
  const double without = EdgeMixture::total(s.e, s.q, local);
  EXPECT_EQ(without, 0.0) << "no environment, no light: no light-aware weight";

  s.q.light_spheres = &s.spheres;
  local_lights(s.q, local);
  ASSERT_EQ(local.size(), 1u) << "the sphere light, seen from outside, is one local light";
  const double with = EdgeMixture::total(s.e, s.q, local);
  EXPECT_GT(with, 0.0) << "the edge crosses the light's cone";

  // The same as the billboard given as a quad light.
  std::vector<LightPolygon> quads(1);
  ASSERT_TRUE(light_billboard(s.spheres[0], s.q.p, quads[0]));
  SilhouetteQuery as_quad = s.q;
  as_quad.light_spheres = nullptr;
  as_quad.lights = &quads;
  std::vector<LocalLight> local_quad;
  local_lights(as_quad, local_quad);
  EXPECT_DOUBLE_EQ(EdgeMixture::total(s.e, as_quad, local_quad), with);

  // An edge beside the light's cone gets none of it.
  Edge away = s.e;
  away.p0 = Vec3(2.0, -1.5, 2.0);
  away.p1 = Vec3(2.5, 2.0, 2.0);
  EXPECT_EQ(EdgeMixture::total(away, s.q, local), 0.0);
}

TEST(LightSphere, LightCoreHoldsTheSphere) {
  SphereLitEdge s;
  s.q.light_spheres = &s.spheres;
  ContourProbe probe;
  int shape = -1;
  ASSERT_TRUE(light_core(s.q, probe, shape));
  EXPECT_EQ(shape, 2);
  TestRng rng(5);
  for (int k = 0; k < 1000; ++k) {
    const Vec3 x = s.spheres[0].centre + unit_vector(rng) * s.spheres[0].radius;
    EXPECT_GE((x - s.q.p).normalized().dot(probe.axis), probe.cos_half_angle - 1e-12);
  }
}

}  // namespace
}  // namespace qsil::edgetree
