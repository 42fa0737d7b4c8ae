// How many secondary boundary traversals a pixel sample makes (boundary_traversals in
// qsil/integrators/boundary_term.h; EstimatorConfig::sppi):
// - a whole rate is exact and draws nothing;
// - a fractional rate picks each sample with probability exactly its fraction (over many pixels,
//   binomial tests at 5 standard deviations), and any run of n consecutive samples of a pixel
//   holds floor or ceil of the fraction times n picks (stratified, unlike Russian roulette);
// - the pick of a sample depends on (seed, pixel, sample) only, so sample ranges and process
//   splits draw the same picks;
// - the estimator stays unbiased at rates 0.5 and 2.5: image sums of a scene whose derivative is
//   the secondary boundary term alone (a floor moving toward a small light: the interior term is
//   exactly zero) agree with rate 1 within 3 combined standard errors (fixed seeds; the films'
//   standard errors weigh the two strata of a fractional rate apart, Film::standard_error), and
//   the method's default is 0.5 for the quadric forest and 1 for the baselines;
// - rates outside 0 or [1/1024, 1024] and primary ratios outside (0, 1024] are refused.
#include "qsil/error.h"
#include "qsil/integrators/boundary_term.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/method.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>

namespace qsil {
namespace {

TEST(BoundaryRate, WholeRatesAreExact) {
  for (double rate : {1.0, 2.0, 3.0})
    for (uint64_t s = 0; s < 50; ++s) EXPECT_EQ(boundary_traversals(rate, 7, 123, s), int(rate));
}

TEST(BoundaryRate, EachSampleIsPickedWithProbabilityTheFraction) {
  // Over 20000 pixels, sample 5 (and sample 0) is picked in a fraction f of them: a binomial
  // count within 5 standard deviations (a correct pick fails with probability ~6e-7).
  for (double f : {0.25, 0.5, 0.7}) {
    for (uint64_t s : {uint64_t(0), uint64_t(5)}) {
      const int n = 20000;
      int picked = 0;
      for (uint64_t pixel = 0; pixel < uint64_t(n); ++pixel) picked += boundary_traversals(1.0 + f, 11, pixel, s) - 1;
      const double sd = std::sqrt(n * f * (1 - f));
      EXPECT_NEAR(picked, n * f, 5 * sd) << "fraction " << f << ", sample " << s;
    }
  }
}

TEST(BoundaryRate, ConsecutiveSamplesOfAPixelHoldTheFractionOfPicksUpToOne) {
  for (double rate : {0.5, 0.3, 2.75})
    for (uint64_t pixel = 0; pixel < 200; ++pixel)
      for (uint64_t first : {uint64_t(0), uint64_t(3), uint64_t(17)})
        for (int n : {1, 2, 7, 64}) {
          int picks = 0;
          for (int s = 0; s < n; ++s) picks += boundary_traversals(rate, 3, pixel, first + uint64_t(s));
          EXPECT_GE(picks, int(std::floor(rate * n))) << rate << " " << pixel << " " << first << " " << n;
          EXPECT_LE(picks, int(std::ceil(rate * n))) << rate << " " << pixel << " " << first << " " << n;
        }
}

TEST(BoundaryRate, MethodDefaults) {
  EXPECT_EQ(default_sppi(Method::Quadric), 0.5);
  EXPECT_EQ(default_sppi(Method::QuadricBox), 0.5);
  EXPECT_EQ(default_sppi(Method::VSphere), 1.0);
  EXPECT_EQ(default_sppi(Method::Uniform), 1.0);
}

/// Image sum and standard error of the plane-light case's derivative at a boundary rate.
ImageSum plane_light_sum(double rate, uint64_t seed, int spp) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/plane-light.xml"), {{"res", "16"}});
  const Estimator e(
      scene, EstimatorConfig::gradient(parse_parameters({"floor:translate:0,1,0"}, scene), Method::Quadric, rate));
  RenderOptions o;
  o.spp = spp;
  o.seed = seed;
  o.threads = 2;
  o.progress = false;
  return e.run(o).film.derivative_sum(0);
}

TEST(BoundaryRate, FractionalRatesStayUnbiased) {
  // At 16 x 16 and 512 spp (rate 1) the image sum's standard error is about 2 % of the sum.
  const ImageSum one = plane_light_sum(1.0, 21, 512);
  ASSERT_GT(std::abs(one.sum), 20 * one.standard_error) << "a clearly non-zero derivative";
  for (double rate : {0.5, 2.5}) {
    const ImageSum r = plane_light_sum(rate, 22, int(std::lround(512 / rate)));
    std::printf("[ measured ] rate %.1f: image sum %.4g +- %.3g; rate 1: %.4g +- %.3g\n", rate, r.sum, r.standard_error,
                one.sum, one.standard_error);
    EXPECT_NEAR(r.sum, one.sum, 3 * std::hypot(r.standard_error, one.standard_error)) << "rate " << rate;
  }
}

TEST(BoundaryRate, BadRatesAreRefused) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/plane-light.xml"), {{"res", "8"}});
  const auto params = parse_parameters({"floor:translate:0,1,0"}, scene);
  for (double rate : {-0.5, 1e-4, 2000.0, double(NAN), double(INFINITY)})
    EXPECT_THROW(Estimator(scene, EstimatorConfig::gradient(params, Method::Quadric, rate)), Error) << rate;
  for (double primary : {0.0, -1.0, 2000.0, double(NAN)})
    EXPECT_THROW(Estimator(scene, EstimatorConfig::gradient(params, Method::Quadric, 0, primary)), Error) << primary;
}

}  // namespace
}  // namespace qsil
