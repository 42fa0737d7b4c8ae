/// @file forest_guiding_test.cpp
/// The quadric method with a forest guide (EstimatorConfig::forest_guiding; forest_guiding.h):
/// - leaves the secondary term's mean unchanged where the guide changes its samples, at res 16:
///   a mesh's self-shadows (spot-selfshadow) and a sphere seen in a mirror (sunk-sphere-mirror),
///   guided - unguided at equal seeds, t-test, 99 %, with power (its standard error below 5 % of
///   the boundary term); the unguided method agrees with finite differences on both
///   (gradient_vs_fd_test.cpp, intersection_curves_test.cpp), so the guided one does. Taking the
///   unguided product alone as the guided path's probability fails the mirror's by 27 s.e.;
/// - is independent of the thread count, training included (set up and run in arenas of 1 and 2
///   threads: bit-identical image sums);
/// - refuses parameters out of range with one-line messages.
/// The exactness of the guided pdf is tested where a guide of random values gives it power:
/// tests/edgetree/forest_guide_test.cpp. Fixed seeds.

#include "estimator_runs.h"
#include "qsil/error.h"
#include "qsil/integrators/estimator.h"
#include "qsil/parameters.h"
#include "test_data.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace qsil {
namespace {

using test::derivative_sum;
using test::message_of;
using test::quiet;

EstimatorConfig guided(const std::vector<ParameterSpec>& params) {
  EstimatorConfig c = EstimatorConfig::gradient(params, Method::Quadric);
  c.forest_guiding.training = 4;
  return c;
}

/// The guided secondary term against the unguided one on `file` at res 16: with the same seed both
/// runs share the interior and the primary term bit for bit (the guided strategy draws from the
/// boundary term's own stream), so guided - unguided per seed is the difference of the two
/// secondary estimates alone; its mean over 8 seeds must be 0 by a t-test with 7 degrees of
/// freedom at |t| < 3.5 (99 %), and its standard error below `power` x the boundary term (unguided
/// - none, first seed). The guide must change the estimate (power: the differences are not all
/// 0). The unguided method's own agreement with finite differences: gradient_vs_fd_test.cpp.
void expect_secondary_term_unchanged(const std::string& file, const std::string& param, int spp, double power) {
  const Scene scene = load_scene(test::data_file(file), {{"res", "16"}});
  const auto params = parse_parameters({param}, scene);
  const Estimator unguided(scene, EstimatorConfig::gradient(params, Method::Quadric));
  const Estimator guide(scene, guided(params));
  const int seeds = 8;
  double diff = 0, diff2 = 0, boundary = 0;
  for (int s = 0; s < seeds; ++s) {
    const RenderOptions o = quiet(spp, uint64_t(61 + s));
    const double u = derivative_sum(unguided.run(o)).value, g = derivative_sum(guide.run(o)).value;
    if (s == 0)
      boundary = u - derivative_sum(Estimator(scene, EstimatorConfig::gradient(params, Method::None)).run(o)).value;
    diff += g - u;
    diff2 += (g - u) * (g - u);
  }
  diff /= seeds;
  const double se = std::sqrt(std::max(0.0, diff2 / seeds - diff * diff) / (seeds - 1));
  std::printf("%s %s: boundary term %.4g, guided - unguided %.4g +- %.3g\n", file.c_str(), param.c_str(), boundary,
              diff, se);
  EXPECT_GT(se, 0) << "the guide changed nothing: the test has no power";
  EXPECT_LT(std::abs(diff), 3.5 * se);
  EXPECT_LT(se, power * std::abs(boundary)) << "power";
}

TEST(ForestGuiding, SelfShadowsOfAMeshAgreeWithTheUnguidedMethod) {
  expect_secondary_term_unchanged("tests/data/gradient/spot-selfshadow.xml", "spot:translate:1,0,0", 256, 0.05);
}

TEST(ForestGuiding, ASphereSeenInAMirrorAgreesWithTheUnguidedMethod) {
  expect_secondary_term_unchanged("tests/data/gradient/sunk-sphere-mirror.xml", "sphere:translate:0,1,0", 256, 0.05);
}

TEST(ForestGuiding, IndependentOfTheThreadCount) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/spot-selfshadow.xml"), {{"res", "8"}});
  const auto params = parse_parameters({"spot:translate:1,0,0"}, scene);
  // The training passes run on the caller's arena: set up and run on 1 and on 2 threads.
  auto run = [&](int threads) {
    double sum = 0;
    tbb::task_arena(threads).execute([&] {
      RenderOptions o = quiet(16, 7);
      o.threads = threads;
      const Estimator e(scene, guided(params));
      EXPECT_EQ(e.setup().structure.find(" 0 cells"), std::string::npos) << "the guide learnt nothing";
      sum = derivative_sum(e.run(o)).value;
    });
    return sum;
  };
  EXPECT_EQ(run(1), run(2));
}

TEST(ForestGuiding, RefusesParametersOutOfRange) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/plane-light.xml"), {{"res", "4"}});
  const auto params = parse_parameters({"floor:translate:0,1,0"}, scene);
  EstimatorConfig c = guided(params);
  c.forest_guiding.training = 1025;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }), "forest guide: training spp 1025 out of range [0, 1024]");
  c.forest_guiding.training = 4;
  c.forest_guiding.rounds = 0;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }), "forest guide: training rounds 0 out of range [1, 16]");
  c.forest_guiding.rounds = 2;
  c.forest_guiding.guide.resolution = 65;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }), "forest guide: resolution 65 out of range [1, 64]");
  c.forest_guiding.guide.resolution = 8;
  c.forest_guiding.guide.depth = -1;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }), "forest guide: depth -1 out of range [0, 8]");
  c.forest_guiding.guide.depth = 3;
  c.forest_guiding.guide.share = 0;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }), "forest guide: defensive share 0.000000 out of range (0, 1]");
  c.forest_guiding.guide.share = 0.5;
  c.method = Method::VSphere;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }),
            "forest guide: method vsphere has no edge forest to guide (quadric, quadric-box)");
}

}  // namespace
}  // namespace qsil
