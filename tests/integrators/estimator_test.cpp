// The estimator layer (qsil/integrators/estimator.h): set up once, run over sample ranges.
// - Two half ranges merged give the film of the full range up to the rounding of the sums, for
//   the primal image, the gradient with every edge-sampling method (a 32 x 32 image: its primary
//   samples are numbered so that the halves draw exactly the full run's) and finite differences.
// - A run is bit-identical for any thread count and when repeated (shadow-quad, and spot-mirror,
//   whose glossy vertices make contour sets); disjoint ranges draw
//   different samples.
// - Set-up builds only what the method samples from: no forest for vsphere, vsphere-solid and
//   uniform, a forest without quadrics for quadric-box, quadrics for quadric.
// - The default FD step moves the parameter's fastest vertex by 1e-3 of the scene's diagonal for
//   every kind (measured on the displaced mesh, not from the formula); 1e-3 when nothing moves.
#include "qsil/integrators/estimator.h"
#include "qsil/error.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>

namespace qsil {
namespace {

Scene shadow_quad(int res) {
  return load_scene(test::data_file("scenes/shadow-quad.xml"),
                    {{"res", std::to_string(res)}, {"spp", "4"}, {"max_depth", "2"}});
}

RenderOptions range(int first, int spp, int threads = 2) {
  RenderOptions o;
  o.first_sample = first;
  o.spp = spp;
  o.seed = 5;
  o.threads = threads;
  o.progress = false;
  return o;
}

/// Every channel of every pixel of `a` equals `b` to `rel` (relative to the channel's scale).
void expect_films_near(const Film& a, const Film& b, double rel, const std::string& what) {
  ASSERT_EQ(a.channels(), b.channels());
  for (int c = 0; c < a.channels(); ++c) {
    double scale = 0;
    for (int y = 0; y < a.height(); ++y)
      for (int x = 0; x < a.width(); ++x) scale = std::max(scale, std::abs(b.mean(c, x, y)));
    for (int y = 0; y < a.height(); ++y)
      for (int x = 0; x < a.width(); ++x) {
        ASSERT_EQ(a.samples(x, y), b.samples(x, y));
        ASSERT_NEAR(a.mean(c, x, y), b.mean(c, x, y), rel * (scale + 1e-300)) << what << " channel " << c;
      }
  }
}

/// Halves [0, 2) and [2, 4) merged vs [0, 4): the same film and image sums up to rounding.
void expect_halves_merge_to_full(const Estimator& e, const std::string& what) {
  RenderResult halves = e.run(range(0, 2));
  halves.merge(e.run(range(2, 2)));
  const RenderResult full = e.run(range(0, 4));
  EXPECT_EQ(halves.spp, 4);
  EXPECT_EQ(halves.traversals, full.traversals) << what;
  expect_films_near(halves.film, full.film, 1e-12, what);
  for (int k = 0; k < e.layout().num_params(); ++k) {
    const ImageSum h = halves.film.derivative_sum(k), f = full.film.derivative_sum(k);
    EXPECT_NEAR(h.sum, f.sum, 1e-12 * (std::abs(f.sum) + f.standard_error)) << what;
    EXPECT_NEAR(h.standard_error, f.standard_error, 1e-9 * f.standard_error) << what;
  }
}

TEST(Estimator, HalfRangesMergeToTheFullRange) {
  const Scene scene = shadow_quad(32);
  const std::vector<ParameterSpec> params{parse_parameter("object:translate:1,0,0", scene)};
  expect_halves_merge_to_full(Estimator(scene, EstimatorConfig::primal()), "primal");
  for (Method m :
       {Method::Quadric, Method::QuadricBox, Method::VSphere, Method::VSphereSolid, Method::Uniform, Method::None})
    expect_halves_merge_to_full(Estimator(scene, EstimatorConfig::gradient(params, m)), std::string(method_name(m)));
  expect_halves_merge_to_full(Estimator(scene, EstimatorConfig::finite_differences(params)), "fd");
}

/// A gradient run is bit-identical for 1 and 2 threads and when repeated (12 x 12 pixels).
void expect_bit_identical_runs(const Scene& scene, const std::string& param) {
  const std::vector<ParameterSpec> params{parse_parameter(param, scene)};
  const Estimator e(scene, EstimatorConfig::gradient(params, Method::Quadric));
  const RenderResult a = e.run(range(3, 2, 1)), b = e.run(range(3, 2, 2)), c = e.run(range(3, 2, 2));
  for (int ch = 0; ch < a.film.channels(); ++ch)
    for (int y = 0; y < 12; ++y)
      for (int x = 0; x < 12; ++x) {
        ASSERT_EQ(a.film.mean(ch, x, y), b.film.mean(ch, x, y));
        ASSERT_EQ(b.film.mean(ch, x, y), c.film.mean(ch, x, y));
        ASSERT_EQ(a.film.standard_error(ch, x, y), b.film.standard_error(ch, x, y));
      }
  EXPECT_EQ(a.first_sample, 3);
  EXPECT_EQ(a.spp, 2);
}

TEST(Estimator, RunsAreBitIdenticalForAnyThreadCountAndWhenRepeated) {
  expect_bit_identical_runs(shadow_quad(12), "object:translate:1,0,0");
  // A glossy mirror: its vertices make contour sets (per-thread scratch storage, probe rays).
  expect_bit_identical_runs(load_scene(test::data_file("scenes/spot-mirror.xml"), {{"res", "12"}, {"spp", "2"}}),
                            "spot:translate:0,1,0");
}

TEST(Estimator, DisjointRangesDrawDifferentSamples) {
  // 12 x 12 pixels: the primary term's chunks straddle sample indices; a range that starts inside
  // a chunk draws it from its own stream, still different from the other range's.
  const Scene scene = shadow_quad(12);
  const std::vector<ParameterSpec> params{parse_parameter("object:translate:1,0,0", scene)};
  const Estimator e(scene, EstimatorConfig::gradient(params, Method::Quadric));
  const RenderResult a = e.run(range(0, 2)), b = e.run(range(2, 2));
  int differ = 0;
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 12; ++x)
      differ += a.film.mean(e.layout().derivative(0, 0), x, y) != b.film.mean(e.layout().derivative(0, 0), x, y);
  EXPECT_GT(differ, 12 * 12 / 4);
}

TEST(Estimator, SetUpBuildsOnlyWhatTheMethodSamplesFrom) {
  const Scene scene = shadow_quad(8);
  const std::vector<ParameterSpec> params{parse_parameter("object:translate:1,0,0", scene)};
  auto setup = [&](Method m) { return Estimator(scene, EstimatorConfig::gradient(params, m)).setup(); };
  const SetupReport quadric = setup(Method::Quadric), box = setup(Method::QuadricBox);
  EXPECT_GT(quadric.fitted_nodes, 0);
  EXPECT_GT(quadric.quadric_nodes, 0);
  EXPECT_EQ(box.fitted_nodes, quadric.fitted_nodes);
  EXPECT_EQ(box.quadric_nodes, 0);
  for (Method m : {Method::VSphere, Method::VSphereSolid, Method::Uniform}) {
    const SetupReport s = setup(m);
    EXPECT_EQ(s.fitted_nodes, 0) << method_name(m);
    EXPECT_EQ(s.quadric_nodes, 0) << method_name(m);
    EXPECT_EQ(s.edges, quadric.edges) << method_name(m);  // the same edge set
    EXPECT_GT(s.primary_edges, 0) << method_name(m);
  }
  const SetupReport none = setup(Method::None);
  EXPECT_EQ(none.structure, "none");
  EXPECT_EQ(none.edges, 0);
}

TEST(Estimator, RejectsBadConfigurationsAndRanges) {
  const Scene scene = shadow_quad(8);
  const ParameterSpec p = parse_parameter("object:translate:1,0,0", scene);
  EXPECT_THROW(Estimator(scene, EstimatorConfig::gradient(std::vector<ParameterSpec>(9, p))), Error);
  EXPECT_THROW(Estimator(scene, EstimatorConfig::finite_differences({p}, {-1.0})), Error);
  EXPECT_THROW(Estimator(scene, EstimatorConfig::finite_differences({p}, {1e-2, 1e-2})), Error);
  const Estimator e(scene, EstimatorConfig::primal());
  EXPECT_THROW(e.run(range(-1, 2)), Error);
  EXPECT_EQ(e.run(range(0, 0)).spp, scene.camera.spp);  // spp <= 0: the scene's sample_count
}

TEST(Estimator, DefaultFiniteDifferenceStepMovesTheFastestVertexByOneThousandthOfTheDiagonal) {
  const Scene scene = shadow_quad(8);
  const double target = 1e-3 * scene.bounds().diagonal();
  for (const char* text : {"object:translate:0,2,0", "object:rotate:1,0,0", "object:rotate:0,1,1@0.3,0,0",
                           "object:scale", "object:scale@1,2,3", "object:vertex:5:0,0,3"}) {
    const std::vector<ParameterSpec> params{parse_parameter(text, scene)};
    const double h = default_fd_step(scene, params[0]);
    const auto moved = displaced_positions(scene, params, 0, h);
    const auto& before = scene.shapes[size_t(params[0].shape)].mesh.positions;
    double largest = 0;
    for (size_t i = 0; i < before.size(); ++i)
      largest = std::max(largest, (moved[size_t(params[0].shape)][i] - before[i]).norm());
    // A rotation by h moves a vertex along the chord 2 sin(h/2) r of its arc h r.
    const double chord = params[0].kind == ParameterSpec::Kind::Rotate ? 2 * std::sin(0.5 * h) / h : 1.0;
    EXPECT_NEAR(largest, chord * target, 1e-9 * target) << text << ", h0 = " << h;
  }
  // A rotation whose axis holds every vertex moves nothing: the fallback step, not a division by 0.
  Scene flat = scene;
  for (Vec3& x : flat.shapes[size_t(flat.find_shape("object"))].mesh.positions) x = Vec3(0, 0, x.z());
  const ParameterSpec axis = parse_parameter("object:rotate:0,0,1@0,0,0", flat);
  EXPECT_EQ(default_fd_step(flat, axis), 1e-3);
}

}  // namespace
}  // namespace qsil
