// The `was` method, warped-area sampling (qsil/integrators/warp_field.h):
// - its auxiliary directions follow the von Mises-Fisher density (the mean cosine, coth k - 1/k,
//   within 4 standard errors at k = 2, 50 and 1e5) and keep 1 - cos exactly;
// - its boundary test is 0 on a triangle's edges, 1 at the incentre, and scale-free;
// - the unbiased warp field (WarpedAreaSampling::unbiased) is, on average, the limit of the
//   fixed-N ratio estimates (oracle: the ratio estimate with 4096 rays), at a direction that
//   grazes an occluder's edge, where a ratio estimate with 2 rays is visibly off;
// - at a direction on a moving outline the many-ray field's component across it is the
//   outline's velocity (within 2 %), the boundary condition the method rests on;
// - a floor sliding in its own plane under a fixed light leaves the image unchanged: every
//   pixel's derivative is zero within 4.5 standard errors (two-sided; 64 pixels, so 4e-4 false
//   alarms per run) although single samples are not, because the pixel border term takes back
//   what the warped samples carry across the pixel's border (without it, pixels are off by many
//   standard errors: checked by removing it);
// - a uniformly lit plane moving toward the camera keeps its image: the image sum is zero within
//   3 standard errors (the camera warp's film Jacobian; inverted, it is 100 standard errors off);
// - where static edges move relative to moving shading points (the floor rising under a light),
//   its image sum agrees with finite differences within 3 combined standard errors (99.7 %
//   two-sided), the combined standard error under 6 % of the value (the unbiased variant is
//   checked on its warp field: its images' standard errors are 4x those of 8 fixed rays, too
//   noisy for a test of power in seconds);
// - its fixed-N bias shrinks with N: on a shadow (an occluder rising toward a light), 2 rays are
//   many standard errors off the quadric method's derivative, 32 rays closer by more than 3
//   combined standard errors;
// - what it refuses, it refuses with a message.
#include "estimator_runs.h"
#include "integrators/light_setup.h"
#include "qsil/error.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/reverse.h"
#include "qsil/integrators/warp_field.h"
#include "qsil/parameters.h"
#include "qsil/ray_tracer.h"
#include "qsil/rng.h"
#include "qsil/sampling.h"
#include "qsil/scene.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <tuple>

namespace qsil {
namespace {

const char* kPlaneLight = "tests/data/gradient/plane-light.xml";
const char* kPenumbra = "tests/data/gradient/penumbra-sign.xml";

using test::derivative_sum;
using test::message_of;
using test::quiet;
using test::Sum;

EstimatorConfig was_config(const std::vector<ParameterSpec>& params, int rays, bool unbiased = false) {
  EstimatorConfig c = EstimatorConfig::gradient(params, Method::WarpedArea);
  c.warped_area.rays = rays;
  c.warped_area.unbiased = unbiased;
  return c;
}

// ---- Building blocks

TEST(WarpedArea, VonMisesFisherDirectionsHaveTheirMeanCosine) {
  for (const double kappa : {2.0, 50.0, 1e5}) {
    Sampler sampler(5, 0, 0);
    const int n = 200000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
      const VonMisesFisherSample s = square_to_von_mises_fisher(sampler.next2(), kappa);
      ASSERT_NEAR(s.dir.norm(), 1.0, 1e-12);
      ASSERT_NEAR(1.0 - s.dir.z(), s.one_minus_cos, 1e-12);
      ASSERT_GE(s.one_minus_cos, 0.0);
      sum += s.one_minus_cos;
      sum2 += s.one_minus_cos * s.one_minus_cos;
    }
    const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
    const double expected = 1.0 - (1.0 / std::tanh(kappa) - 1.0 / kappa);  // E[1 - cos]
    EXPECT_NEAR(mean, expected, 4 * se) << "kappa " << kappa;
    EXPECT_LT(se, 0.01 * expected) << "power";
  }
  // The density integrates to one over the sphere (kappa = 50: the integrand in 1 - cos).
  double integral = 0;
  const int m = 200000;
  for (int i = 0; i < m; ++i) integral += von_mises_fisher_pdf(2.0 * (i + 0.5) / m, 50.0) * 2 * kPi * 2.0 / m;
  EXPECT_NEAR(integral, 1.0, 1e-6);
}

TEST(WarpedArea, BoundaryTestIsZeroOnEdgesOneAtTheIncentreAndScaleFree) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), dir(0, 0, -1);
  const double r = 1.0 / (2.0 + std::sqrt(2.0));  // the right triangle's inradius
  EXPECT_NEAR(triangle_boundary_test(a, b, c, Vec3(r, r, 0), dir), 1.0, 1e-12);
  EXPECT_NEAR(triangle_boundary_test(a, b, c, Vec3(0.5, 0, 0), dir), 0.0, 1e-15);
  EXPECT_NEAR(triangle_boundary_test(a, b, c, Vec3(0.5, 0.5, 0), dir), 0.0, 1e-15);
  EXPECT_NEAR(triangle_boundary_test(a, b, c, a, dir), 0.0, 1e-15);
  EXPECT_NEAR(triangle_boundary_test(a, b, c, Vec3(0.1, 0.2, 0), dir), 0.1 / r, 1e-12);
  for (const double scale : {1e-3, 1e4})
    EXPECT_NEAR(triangle_boundary_test(a * scale, b * scale, c * scale, Vec3(0.1, 0.2, 0) * scale, dir), 0.1 / r, 1e-9);
  // Seen edge-on: all boundary.
  EXPECT_EQ(triangle_boundary_test(a, b, c, Vec3(0.2, 0.2, 0), Vec3(1, 0, 0)), 0.0);
}

// The warp field from a static floor point of penumbra-sign while the occluder rises
// (occluder:translate:0,1,0): the set-up of the two field tests below.
struct RisingOccluder {
  const Scene scene = load_scene(test::data_file(kPenumbra), {{"res", "8"}});
  const SceneVelocities vel = compute_velocities(scene, parse_parameters({"occluder:translate:0,1,0"}, scene));
  const RayTracer tracer{scene};
  const LightSetup lights{scene};
  const PathContext ctx = lights.context(scene, tracer);
  const DualView<1> view{&scene, &vel};
  /// warp_field of direction w at the static floor point p (auxiliary rays offset 1e-6 above it).
  WarpedDirection<Dual<1>> warp(const WarpedAreaSampling& was, const Vec3& p, const Vec3& w, Sampler& aux) const {
    PathStats stats;
    const auto spawn = [&](const Vec3&) { return Vec3(p + Vec3(0, 1e-6, 0)); };
    return warp_field(ctx, view, was, lift<Dual<1>>(p), true, w, spawn, false, aux, stats);
  }
};

// From a floor point of penumbra-sign just outside the occluder's shadow (x = 0.35), toward the
// light past the occluder's edge x = 0.3 (y = 1) by a small angle: the occluder rises
// (occluder:translate:0,1,0), so the edge moves across the direction.
TEST(WarpedArea, UnbiasedFieldIsTheLimitOfTheRatioEstimates) {
  const RisingOccluder occluder;
  const Vec3 p(0.35, 0, 0.05);
  const Vec3 w = Vec3(-0.05 + 0.002, 1, 0).normalized();
  struct Mean {
    double sum = 0, sum2 = 0;
    int n = 0;
    void add(double x) { sum += x, sum2 += x * x, ++n; }
    double mean() const { return sum / n; }
    double se() const { return std::sqrt((sum2 / n - mean() * mean()) / n); }
  };
  // The velocity across the edge (x) and the divergence, per estimate.
  const auto estimate = [&](const WarpedAreaSampling& was, Sampler& aux, Mean& vx, Mean& div) {
    const WarpedDirection<Dual<1>> r = occluder.warp(was, p, w, aux);
    vx.add(r.dir.x().derivatives()[0]);
    div.add(r.jacobian.derivatives()[0]);
  };
  WarpedAreaSampling limit;
  limit.rays = 4096;
  Mean limit_vx, limit_div;
  for (int i = 0; i < 64; ++i) {
    Sampler aux(7, 0, uint64_t(i));
    estimate(limit, aux, limit_vx, limit_div);
  }
  WarpedAreaSampling unbiased;
  unbiased.rays = 8;
  unbiased.unbiased = true;
  WarpedAreaSampling two;
  two.rays = 2;
  Mean u_vx, u_div, t_vx, t_div;
  for (int i = 0; i < 40000; ++i) {
    Sampler aux(8, 0, uint64_t(i));
    estimate(unbiased, aux, u_vx, u_div);
    Sampler aux2(9, 0, uint64_t(i));
    estimate(two, aux2, t_vx, t_div);
  }
  std::printf("v_x: limit %.5g +- %.2g, unbiased %.5g +- %.2g, 2 rays %.5g +- %.2g\n", limit_vx.mean(), limit_vx.se(),
              u_vx.mean(), u_vx.se(), t_vx.mean(), t_vx.se());
  std::printf("div: limit %.5g +- %.2g, unbiased %.5g +- %.2g, 2 rays %.5g +- %.2g\n", limit_div.mean(), limit_div.se(),
              u_div.mean(), u_div.se(), t_div.mean(), t_div.se());
  ASSERT_GT(std::abs(limit_vx.mean()), 10 * limit_vx.se()) << "the edge must move across the direction";
  for (const auto& [lim, unb, two_rays] : {std::tuple{limit_vx, u_vx, t_vx}, std::tuple{limit_div, u_div, t_div}}) {
    const double se = std::hypot(lim.se(), unb.se());
    EXPECT_NEAR(unb.mean(), lim.mean(), 4 * se);
    EXPECT_LT(se, 0.1 * std::abs(lim.mean())) << "power";
    EXPECT_GT(std::abs(two_rays.mean() - lim.mean()), 5 * std::hypot(lim.se(), two_rays.se()))
        << "2 rays must be visibly biased for the comparison to mean anything";
  }
}

// The boundary condition that makes the warp work ([WAS] Eq. 9): at a direction on a moving
// outline, the field's component across the outline is the outline's velocity. From the floor
// point (0.6, 0, 0.1) of penumbra-sign, in the middle of the penumbra, toward the rising occluder's
// edge x = 0.3, y = 1 (behind it, the light's interior off its diagonal: a triangle edge there
// would take half the weight: at z = 0 the field was 0.146 against the edge's 0.275): the
// 4096-ray field across the edge within 2 % of d/dtheta normalize(e - p) across it (measured:
// 0.015 %), while two lobe widths beside it on the lit side (the aux rays there see the static
// light) it is well below.
TEST(WarpedArea, FieldAtAnOutlineIsTheOutlinesVelocity) {
  const RisingOccluder occluder;
  const Vec3 p(0.6, 0, 0.1);
  const Vec3 e(0.3, 1, 0.1);  // a point of the occluder's edge (along z)
  const Vec3 wb = (e - p).normalized();
  const Vec3 across = wb.cross(Vec3(0, 0, 1)).normalized();  // normal to the outline on the sphere
  const double outline_speed = ((Vec3(0, 1, 0) - wb * wb.y()) / (e - p).norm()).dot(across);
  WarpedAreaSampling many;
  many.rays = 4096;
  const auto field_across = [&](const Vec3& w) {
    double sum = 0;
    for (int i = 0; i < 8; ++i) {
      Sampler aux(13, 0, uint64_t(i));
      const WarpedDirection<Dual<1>> r = occluder.warp(many, p, w, aux);
      sum += Vec3(r.dir.x().derivatives()[0], r.dir.y().derivatives()[0], r.dir.z().derivatives()[0]).dot(across) / 8;
    }
    return sum;
  };
  const double on = field_across(wb);
  // 2 / sqrt(kappa) toward the lit side (the light is static: velocity 0 there).
  const double beside =
      field_across((wb + across * (2.0 / std::sqrt(many.kappa)) * (across.x() > 0 ? 1 : -1)).normalized());
  std::printf("across the outline: field %.5g, outline %.5g; beside it %.5g\n", on, outline_speed, beside);
  EXPECT_NEAR(on, outline_speed, 0.02 * std::abs(outline_speed));
  EXPECT_LT(std::abs(beside), 0.8 * std::abs(outline_speed));
}

// ---- Images

TEST(WarpedArea, FloorSlidingInItsPlaneLeavesEveryPixelUnchanged) {
  const Scene scene = load_scene(test::data_file(kPlaneLight), {{"res", "8"}});
  const auto params = parse_parameters({"floor:translate:1,0,0"}, scene);
  const Estimator e(scene, was_config(params, 8));
  const RenderResult r = e.run(quiet(2048, 3));
  const FilmLayout& layout = e.layout();
  double largest_z = 0, mean_se = 0;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      const int c = layout.derivative_mean(0);
      const double m = r.film.mean(c, x, y), se = r.film.standard_error(c, x, y);
      ASSERT_GT(se, 0) << "single samples carry derivatives (" << x << ", " << y << ")";
      largest_z = std::max(largest_z, std::abs(m) / se);
      mean_se += se / 64;
    }
  std::printf("sliding floor: largest |z| %.2f over 64 pixels, mean standard error %.3g\n", largest_z, mean_se);
  EXPECT_LT(largest_z, 4.5);
}

// uniform-plane.xml: a plane under a constant sky, seen from above with a 90 deg field of view,
// moving toward the camera: the image does not change. The camera's warp stretches the film (its
// Jacobian's cos^3 factor) and moves samples across pixel borders; with 32 rays the image sum is
// zero within 3 standard errors (with the film Jacobian's factor inverted it was -35.7 +- 0.3, and
// with 2 rays, the fixed-N bias, -6.0 +- 0.3).
TEST(WarpedArea, UniformPlaneMovingTowardTheCameraKeepsItsImage) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/uniform-plane.xml"), {{"res", "8"}});
  const auto params = parse_parameters({"plane:translate:0,1,0"}, scene);
  const Sum g = derivative_sum(Estimator(scene, was_config(params, 32)).run(quiet(2048, 31)));
  std::printf("uniform plane toward the camera: was %.4g +- %.3g\n", g.value, g.se);
  EXPECT_NEAR(g.value, 0.0, 3 * g.se);
  EXPECT_LT(g.se, 1.0) << "power: an inverted film Jacobian is off by 36";
}

TEST(WarpedArea, StaticLightEdgesSeenFromMovingPointsAgreeWithFiniteDifferences) {
  const Scene scene = load_scene(test::data_file(kPlaneLight), {{"res", "8"}});
  const auto params = parse_parameters({"floor:translate:0,1,0"}, scene);
  const Sum fd = derivative_sum(Estimator(scene, EstimatorConfig::finite_differences(params)).run(quiet(4096, 11)));
  const Sum g = derivative_sum(Estimator(scene, was_config(params, 8)).run(quiet(4096, 12)));
  const double se = std::hypot(g.se, fd.se);
  std::printf("floor rising, was: %.4g +- %.3g, fd %.4g +- %.3g, z %.2f\n", g.value, g.se, fd.value, fd.se,
              (g.value - fd.value) / se);
  EXPECT_NEAR(g.value, fd.value, 3 * se);
  EXPECT_LT(se, 0.06 * std::abs(fd.value)) << "power";
}

TEST(WarpedArea, FixedNBiasShrinksWithTheRays) {
  const Scene scene = load_scene(test::data_file(kPenumbra), {{"res", "8"}});
  const auto params = parse_parameters({"occluder:translate:0,1,0"}, scene);
  const Sum hard =
      derivative_sum(Estimator(scene, EstimatorConfig::gradient(params, Method::Quadric)).run(quiet(4096, 21)));
  const Sum few = derivative_sum(Estimator(scene, was_config(params, 2)).run(quiet(1024, 22)));
  const Sum many = derivative_sum(Estimator(scene, was_config(params, 32)).run(quiet(1024, 23)));
  std::printf("occluder rising: quadric %.4g +- %.3g, was 2 rays %.4g +- %.3g, 32 rays %.4g +- %.3g\n", hard.value,
              hard.se, few.value, few.se, many.value, many.se);
  const double few_bias = std::abs(few.value - hard.value), many_bias = std::abs(many.value - hard.value);
  EXPECT_GT(few_bias, 5 * std::hypot(few.se, hard.se)) << "2 rays' bias must be visible";
  EXPECT_GT(few_bias - many_bias, 3 * std::hypot(few.se, many.se));
}

TEST(WarpedArea, RefusesWhatItCannotDo) {
  const Scene scene = load_scene(test::data_file(kPlaneLight), {{"res", "4"}});
  const auto params = parse_parameters({"floor:translate:0,1,0"}, scene);
  EstimatorConfig c = was_config(params, 0);
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }), "was: auxiliary rays 0 out of range [1, 1024]");
  c = was_config(params, 8);
  c.warped_area.exponent = 1;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }), "was: exponent 1.000000 out of range (1, 16]");
  RenderOptions o = quiet(1, 1);
  o.largest_samples = 2;
  EXPECT_EQ(message_of([&] { Estimator(scene, was_config(params, 8)).run(o); }),
            "was: the largest samples' paths are not traced for this method");
  EXPECT_EQ(message_of([&] {
              ReverseEstimator(scene, ReverseConfig{{0}, Method::WarpedArea, 1});
            }),
            "reverse mode: method was is not supported (forward mode only: qsil grad)");
}

}  // namespace
}  // namespace qsil
