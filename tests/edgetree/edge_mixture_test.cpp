/// @file edge_mixture_test.cpp
/// Tests of edgetree/edge_mixture.h and the edge importances of silhouette_sampler.h: an
/// EdgePointSampler restricted to [t_lo, t_hi] is a density on that interval alone; the light-aware
/// mixture is a density on [0, 1] that is positive everywhere, its samples follow it (chi-square),
/// its total() is the radiance-weighted LTC integral, computed here by quadrature with an
/// independent oracle for "the direction w(t) sees the light" (a ray-quad intersection), and it
/// estimates that integral with less variance than the plain sampler. velocity_factor vanishes for
/// an edge moving within the plane through p and itself (where J = 0) and only there.
///
/// Quadrature: composite midpoint rule, 100 bins x 2000 points (error < 1e-7 relative, as in
/// edge_point_sampler_test.cpp). Chi-square: 100 bins, 2e5 samples, significance 1 %. Fixed seeds.

#include "edgetree/edge_mixture.h"

#include "bin_quadrature.h"
#include "chi2.h"
#include "ray_hits.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace qsil::edgetree {
namespace {

using test::ray_hits_quad;
using test::TestRng;

using test::bin_integrals;
using test::kBins;
using test::sum;

/// p at the origin, shading normal +z, GGX alpha 0.3 seen from 35 degrees; an edge crossing the
/// lobe at height 2; a quad light at height 3 facing down that covers the middle of the edge.
struct LitEdge {
  SilhouetteQuery q;
  Edge e;
  std::vector<LightPolygon> lights;
  std::vector<double> emission{0.0, 0.0};
  LitEdge(double env, double light_radiance) {
    q.p = Vec3::Zero();
    q.frame = Frame(Vec3::UnitZ());
    const Vec3 wo(std::sin(0.6), 0.0, std::cos(0.6));
    q.ltc = ltc_ggx(0.3, q.frame.to_local(wo));
    q.env_weight = env;
    e.p0 = Vec3(-2.5, -1.5, 2.0);
    e.p1 = Vec3(0.5, 2.0, 2.0);
    e.length = (e.p1 - e.p0).norm();
    e.shape = 1;
    LightPolygon l;
    l.corners = {Vec3(-1.5, -0.4, 3.0), Vec3(-1.5, 0.8, 3.0), Vec3(-0.3, 0.8, 3.0), Vec3(-0.3, -0.4, 3.0)};
    l.normal = Vec3(0, 0, -1);
    l.weight = light_radiance;
    lights.push_back(l);
    q.lights = &lights;
    q.emission = &emission;
  }
  Vec3 w(double t) const { return q.frame.to_local(e.p0 + t * (e.p1 - e.p0) - q.p); }
  /// The radiance that can jump at t: the environment's, the light's where w(t) sees it, the
  /// edge's own shape's emission.
  double radiance(double t) const {
    std::array<Vec3, 4> c;
    for (int i = 0; i < 4; ++i) c[size_t(i)] = q.frame.to_local(lights[0].corners[size_t(i)] - q.p);
    return q.env_weight + (ray_hits_quad(w(t), c) ? lights[0].weight : 0.0) + emission[size_t(e.shape)];
  }
};

TEST(EdgeMixtureTest, RestrictedSamplerIsADensityOnItsInterval) {
  const LitEdge s(1.0, 0.0);
  const EdgePointSampler full(s.w(0), s.w(1), s.q.ltc);
  const EdgePointSampler part(s.w(0), s.w(1), s.q.ltc, kEdgeDefensiveShare, 0.3, 0.55);
  EXPECT_EQ(part.ltc_pdf(0.29), 0.0);
  EXPECT_EQ(part.ltc_pdf(0.56), 0.0);
  EXPECT_NEAR(sum(bin_integrals([&](double t) { return part.ltc_pdf(t); })), 1.0, 1e-6);
  const double expected = sum(bin_integrals([&](double t) { return t >= 0.3 && t <= 0.55 ? full.target(t) : 0.0; }));
  EXPECT_NEAR(part.target_integral(), expected, 1e-5 * expected);
  TestRng rng(5);
  for (int i = 0; i < 10000; ++i) {
    const double t = part.sample_ltc(rng.uniform());
    ASSERT_GE(t, 0.3);
    ASSERT_LE(t, 0.55);
  }
}

TEST(EdgeMixtureTest, TotalIsTheRadianceWeightedIntegral) {
  for (double env : {0.0, 0.05, 1.0}) {
    LitEdge s(env, 20.0);
    const EdgePointSampler plain(s.w(0), s.w(1), s.q.ltc);
    const double expected = sum(bin_integrals([&](double t) { return plain.target(t) * s.radiance(t); }));
    const EdgeMixture m(s.e, s.q);
    EXPECT_NEAR(m.total(), expected, 2e-3 * expected) << "env " << env;
    // An emitter's outline: its own radiance over the whole edge.
    s.emission[1] = 3.0;
    const double with_emission = sum(bin_integrals([&](double t) { return plain.target(t) * s.radiance(t); }));
    EXPECT_NEAR(EdgeMixture(s.e, s.q).total(), with_emission, 2e-3 * with_emission) << "env " << env;
  }
}

// The importance the traversal computes for every candidate edge (EdgeMixture::total without a
// mixture, from the endpoints mapped once into the LTC's cosine domain: ltc_integral_mapped) is
// the sampled mixture's total up to rounding, over shading frames, roughnesses, edges crossing
// the shading horizon, lights crossed or missed, emission on and off; and zero only where the
// sampler's integral is (a zero importance where the integral is not would leave the edge to the
// defensive share alone). The relative tolerance 1e-9 is far above the rounding of either form
// (at most 1.1e-13 over these cases) and far below any error of the closed form: dropping one
// term of F, or the |d| of h, fails it.
TEST(EdgeMixtureTest, ImportanceWithoutTheMixtureIsItsTotal) {
  TestRng rng(17);
  int lit = 0, clipped = 0;
  for (int i = 0; i < 500; ++i) {
    LitEdge s(rng.uniform(), 40.0 * rng.uniform());
    const Vec3 n = Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform()).normalized();
    s.q.frame = Frame(n);
    const Vec3 wo = Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, 1.0).normalized();
    s.q.ltc = i % 3 == 0 ? ltc_diffuse() : ltc_ggx(0.01 + rng.uniform(), wo);
    s.emission[1] = i % 2 ? 2.0 : 0.0;
    s.e.p1 += Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
    if (i % 4 == 1) s.e.p0 = Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, -2.0 * rng.uniform());  // below
    std::vector<LocalLight> lights;
    local_lights(s.q, lights);
    const EdgeMixture m(s.e, s.q, lights);
    const double total = EdgeMixture::total(s.e, s.q, lights);
    ASSERT_NEAR(total, m.total(), 1e-9 * m.total()) << "case " << i;
    ASSERT_EQ(total > 0, m.total() > 0) << "case " << i;
    const double exact = EdgePointSampler(s.w(0), s.w(1), s.q.ltc, kEdgeDefensiveShare, 0.2, 0.7).target_integral();
    const LtcMap map(s.q);
    const EdgeGeometry g(s.e, s.q.p);
    const double mapped =
        EdgePointSampler::ltc_integral_mapped(map.to_cosine * g.w0, map.to_cosine * g.w1, map.normal.dot(g.w0),
                                              map.normal.dot(g.w1), g.normal_len, map.scale, 0.2, 0.7);
    ASSERT_NEAR(mapped, exact, 1e-9 * exact) << "case " << i;
    ASSERT_EQ(mapped > 0, exact > 0) << "case " << i;
    const double unlit = (s.q.env_weight + s.emission[1]) * EdgePointSampler(s.w(0), s.w(1), s.q.ltc).target_integral();
    lit += m.total() > 1.001 * unlit;
    clipped += s.w(0).z() < 0 && m.total() > 0;
  }
  EXPECT_GT(clipped, 20);  // edges cut by the shading horizon are exercised
  EXPECT_GT(lit, 50);  // the light's component is exercised
}

TEST(EdgeMixtureTest, PdfIsNormalisedPositiveAndSampled) {
  const int n = 200000;
  TestRng rng(77);
  for (double env : {0.0, 0.05, 1.0}) {
    const LitEdge s(env, 20.0);
    const EdgeMixture m(s.e, s.q);
    // The light's component jumps where w(t) crosses the light's outline: there the midpoint rule
    // errs by up to jump x h / 2 (h = 5e-6; jumps of a few units here), hence 1e-4.
    EXPECT_NEAR(sum(bin_integrals([&](double t) { return m.pdf(t); })), 1.0, 1e-4) << "env " << env;
    for (int k = 0; k <= 1000; ++k) ASSERT_GT(m.pdf(k / 1000.0), 0.0) << "env " << env << " t " << k / 1000.0;
    EXPECT_EQ(m.pdf(-1e-9), 0.0);
    EXPECT_EQ(m.pdf(1 + 1e-9), 0.0);
    std::vector<double> observed(kBins, 0.0);
    for (int i = 0; i < n; ++i) {
      const EdgePointSample smp = m.sample(rng.uniform());
      ASSERT_GE(smp.t, 0.0);
      ASSERT_LE(smp.t, 1.0);
      ASSERT_EQ(smp.pdf, m.pdf(smp.t));
      observed[size_t(std::min(kBins - 1, int(smp.t * kBins)))] += 1;
    }
    std::vector<double> expected = bin_integrals([&](double t) { return m.pdf(t); });
    for (double& x : expected) x *= n;
    const test::Chi2Result r = test::chi2_test(observed, expected, test::sidak(0.01, 3));
    EXPECT_TRUE(r.passed) << "env " << env << ": " << r.message;
  }
}

TEST(EdgeMixtureTest, EstimatesTheRadianceWeightedIntegralWithLessVariance) {
  // The integrand of the boundary term along the edge, up to J: target x radiance. A dim
  // environment and a bright light: the plain sampler spends most samples where the light is not.
  const LitEdge s(0.05, 20.0);
  const EdgePointSampler plain(s.w(0), s.w(1), s.q.ltc);
  const EdgeMixture m(s.e, s.q);
  const double ref = sum(bin_integrals([&](double t) { return plain.target(t) * s.radiance(t); }));
  TestRng rng(3);
  const int n = 100000;
  double sp = 0, sp2 = 0, sm = 0, sm2 = 0;
  for (int i = 0; i < n; ++i) {
    const EdgePointSample a = plain.sample(rng.uniform()), b = m.sample(rng.uniform());
    const double fa = plain.target(a.t) * s.radiance(a.t) / a.pdf, fb = plain.target(b.t) * s.radiance(b.t) / b.pdf;
    sp += fa;
    sp2 += fa * fa;
    sm += fb;
    sm2 += fb * fb;
  }
  const double vp = sp2 / n - (sp / n) * (sp / n), vm = sm2 / n - (sm / n) * (sm / n);
  EXPECT_NEAR(sm / n, ref, 5 * std::sqrt(vm / n));  // unbiased (5 standard errors)
  std::printf("[EdgeMixture] variance plain / mixture = %.3g\n", vp / vm);
  EXPECT_GT(vp / vm, 4.0);
}

TEST(EdgeMixtureTest, VelocityFactorVanishesOnlyForMotionWithinThePlane) {
  LitEdge s(1.0, 0.0);
  SceneVelocities vel;
  vel.num_params = 1;
  vel.position.assign(2, std::vector<SceneVelocities::Block>(2, SceneVelocities::Block::Zero()));
  s.e.v0 = 0;
  s.e.v1 = 1;
  s.q.velocities = &vel;
  s.q.velocity_scale[0] = 1.0;
  const Vec3 n = (s.e.p0 - s.q.p).cross(s.e.p1 - s.q.p).normalized();
  const Vec3 in_plane = (s.e.p1 - s.e.p0).normalized();
  vel.position[1][0].col(0) = in_plane;
  vel.position[1][1].col(0) = 2.0 * in_plane;
  EXPECT_NEAR(velocity_factor(s.e, s.q), 0.0, 1e-15);
  // p moving with the edge: relative velocity 0.
  vel.position[1][0].col(0) = vel.position[1][1].col(0) = Vec3(0.3, -0.2, 0.7);
  s.q.dp.col(0) = Vec3(0.3, -0.2, 0.7);
  EXPECT_NEAR(velocity_factor(s.e, s.q), 0.0, 1e-15);
  // A rotation about the edge's midpoint's normal line: n . v is +1 at one end and -1 at the
  // other (0 at the middle), yet the factor is the mean of |n . v| over the edge's ends, 1.
  s.q.dp.setZero();
  vel.position[1][0].col(0) = n;
  vel.position[1][1].col(0) = -n;
  EXPECT_NEAR(velocity_factor(s.e, s.q), 1.0, 1e-12);
  // Without velocities the factor is 1; a static edge seen from a moving p: |n . dp|.
  vel.position[1][0].col(0).setZero();
  vel.position[1][1].col(0).setZero();
  s.q.dp.col(0) = 0.5 * n + in_plane;
  EXPECT_NEAR(velocity_factor(s.e, s.q), 0.5, 1e-12);
  s.q.velocities = nullptr;
  EXPECT_EQ(velocity_factor(s.e, s.q), 1.0);
}

}  // namespace
}  // namespace qsil::edgetree
