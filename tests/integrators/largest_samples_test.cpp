// RenderOptions::largest_samples (qsil/integrators/sample_trace.h): the samples of largest
// |derivative| of a gradient run and their retraced paths.
// - Replay: with no boundary term (Method::None) a sample is its interior term, and the retrace
//   from the sample's own stream must reproduce it exactly (a retrace from the wrong stream, or a
//   path that differs, fails this); with the quadric boundary term the interior part is the same
//   sample retraced, so it equals the None run's value of that sample.
// - Bookkeeping: the camera's emission plus what each vertex adds is the interior term, and so is
//   the camera's emission plus what arises at each vertex (with an attached camera ray, whose
//   Jacobian term the first vertex takes).
// - Attribution: on `two-mirrors`, a static flat mirror lit by an environment map collects light
//   but adds no derivative of its own, so nothing arises there, however much it adds.
// - Order and coverage: largest first; the largest |sample| bounds every pixel's |mean| (a mean
//   of samples), and the kept samples do not depend on the thread count.
// Scene: `direct` (Spot in front of a backdrop under an environment map) at 16², 16 spp.
#include "qsil/integrators/estimator.h"
#include "qsil/scene.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tuple>

namespace qsil {
namespace {

struct DirectRun {
  RenderResult result;
  FilmLayout layout;
};

DirectRun run_direct(Method method, int threads, int keep = 8, CameraHits hits = CameraHits::Adaptive) {
  static const Scene scene = load_scene(test::data_file("scenes/direct.xml"), {{"res", "16"}, {"spp", "16"}});
  const std::vector<ParameterSpec> params{parse_parameter("spot:translate:1,0,0", scene)};
  EstimatorConfig config = EstimatorConfig::gradient(params, method);
  config.camera_hits = hits;
  const Estimator e(scene, config);
  RenderOptions o;
  o.progress = false;
  o.seed = 3;
  o.threads = threads;
  o.largest_samples = keep;
  return {e.run(o), e.layout()};
}

// A sample's interior term summed two ways, with the scale of the parts (for rounding bounds):
// camera emission + Jacobian term + what each vertex adds, and camera emission + what arises at
// each vertex.
struct InteriorSums {
  double added = 0, arises = 0, scale = 0;
};
InteriorSums interior_sums(const SampleTrace& s) {
  InteriorSums r{s.camera_emission + s.camera_jacobian, s.camera_emission, std::abs(s.interior)};
  for (const VertexTrace& v : s.vertices) {
    r.added += v.added;
    r.arises += v.arises;
    r.scale += std::abs(v.added) + std::abs(v.arises);
  }
  return r;
}

TEST(LargestSamples, RetraceReproducesTheInteriorTerm) {
  const DirectRun none = run_direct(Method::None, 2);
  ASSERT_EQ(none.result.largest.size(), 8u);
  for (const SampleTrace& s : none.result.largest) {
    EXPECT_EQ(s.interior, s.value) << "pixel (" << s.x << ", " << s.y << ") sample " << s.sample;
    ASSERT_FALSE(s.vertices.empty());
    EXPECT_EQ(s.camera_jacobian, 0.0);
    const InteriorSums sums = interior_sums(s);
    EXPECT_NEAR(sums.added, s.interior, 1e-12 * std::abs(s.interior)) << "the vertices' parts sum to the interior term";
    EXPECT_NEAR(sums.arises, s.interior, 1e-12 * sums.scale) << "so do the parts that arise at them";
  }
  // With the boundary term, the interior part of a sample is the same path's derivative. Camera
  // hits detached: at 16 x 16 the adaptive rule attaches Spot's sharpest smoothed creases, and an
  // attached sample's interior part is the attached form's (warped ray, Jacobian), which Method::None
  // (no primary term, so never attached) does not compute.
  const DirectRun quadric = run_direct(Method::Quadric, 2, 64, CameraHits::Detached);
  std::map<std::tuple<int, int, int>, double> interior;
  for (const SampleTrace& s : run_direct(Method::None, 2, 100000).result.largest) interior[{s.x, s.y, s.sample}] = s.value;
  int compared = 0;
  for (const SampleTrace& s : quadric.result.largest) {
    const auto it = interior.find({s.x, s.y, s.sample});
    const double expected = it == interior.end() ? 0.0 : it->second;  // absent: a zero interior term
    EXPECT_EQ(s.interior, expected) << "pixel (" << s.x << ", " << s.y << ") sample " << s.sample;
    ++compared;
  }
  EXPECT_EQ(compared, 64);
}

// With attached camera hits the retrace's interior term holds the warp's Jacobian term: outside
// every vertex's `added`, inside the first vertex's `arises`.
TEST(LargestSamples, AnAttachedRaysJacobianArisesAtTheFirstVertex) {
  const DirectRun run = run_direct(Method::Quadric, 2, 32, CameraHits::Attached);
  int with_jacobian = 0;
  for (const SampleTrace& s : run.result.largest) {
    const InteriorSums sums = interior_sums(s);
    EXPECT_NEAR(sums.added, s.interior, 1e-12 * sums.scale)
        << "pixel (" << s.x << ", " << s.y << ") sample " << s.sample;
    EXPECT_NEAR(sums.arises, s.interior, 1e-12 * sums.scale)
        << "pixel (" << s.x << ", " << s.y << ") sample " << s.sample;
    with_jacobian += s.camera_jacobian != 0;
  }
  EXPECT_GT(with_jacobian, 0) << "no attached sample among the largest: the test sees nothing";
}

// two-mirrors: the bunny seen directly and in two GGX alpha 0.01 mirrors under an environment map.
// A path camera -> bunny -> mirror collects at the mirror the sky it reflects, and the sample's
// derivative is the bunny hit's (its normal turns as it slides, detached): at the static, flat
// mirror, the light sample's and the escape's directions are fixed, so what it collects has no
// derivative of its own, and the factor it would pass on has none either. `arises` must be ~0 there
// while `added` carries the sample.
TEST(LargestSamples, NothingArisesAtAStaticMirrorThatCollectsTheLight) {
  const Scene scene = load_scene(test::data_file("scenes/two-mirrors.xml"), {{"res", "24"}, {"spp", "32"}});
  std::vector<bool> mirror(scene.shapes.size(), false);
  for (size_t i = 0; i < scene.shapes.size(); ++i)
    mirror[i] = scene.shapes[i].id == "mirror-left" || scene.shapes[i].id == "mirror-right";
  const std::vector<ParameterSpec> params{parse_parameter("bunny:translate:1,0,0", scene)};
  EstimatorConfig config = EstimatorConfig::gradient(params, Method::None);
  config.camera_hits = CameraHits::Detached;
  const Estimator e(scene, config);
  RenderOptions o;
  o.progress = false;
  o.seed = 5;
  o.threads = 2;
  o.largest_samples = 64;
  const RenderResult r = e.run(o);
  int checked = 0, carried = 0;
  for (const SampleTrace& s : r.largest) {
    if (s.vertices.size() < 2 || mirror[size_t(s.vertices[0].shape)] || !mirror[size_t(s.vertices[1].shape)]) continue;
    const VertexTrace& at_mirror = s.vertices[1];
    EXPECT_LE(std::abs(at_mirror.arises), 1e-9 * std::abs(s.interior))
        << "pixel (" << s.x << ", " << s.y << ") sample " << s.sample << ": adds " << at_mirror.added;
    ++checked;
    carried += std::abs(at_mirror.added) >= 0.5 * std::abs(s.interior);
  }
  EXPECT_GT(checked, 0) << "no kept path meets a mirror after the bunny";
  EXPECT_GT(carried, 0) << "no kept sample is collected mostly at a mirror: the test cannot tell the two rules apart";
}

// The retrace evaluates the sample's secondary boundary term again, from its own stream, beside
// the path (BoundaryPointRecorder): the sum of its edge points is the sample's value - interior
// (a wrong stream, traversal count or query gives other points and fails this), and the largest
// point's recorded factors are those of a contributing point (pdf, jump, g . v nonzero).
// Both camera-hit forms: an attached sample's derivative is L times a Jacobian of value 1, so its
// boundary part (value 0) is unchanged by it and the sum holds alike.
class RetraceRecordsTheBoundaryTerm : public testing::TestWithParam<CameraHits> {};

TEST_P(RetraceRecordsTheBoundaryTerm, SumIsTheSamplesBoundaryPart) {
  const DirectRun quadric = run_direct(Method::Quadric, 2, 64, GetParam());
  int with_points = 0;
  for (const SampleTrace& s : quadric.result.largest) {
    const BoundaryPointTrace& b = s.boundary;
    const double boundary = s.value - s.interior;
    EXPECT_NEAR(b.total, boundary, 1e-9 * (std::abs(s.value) + std::abs(s.interior)))
        << "pixel (" << s.x << ", " << s.y << ") sample " << s.sample;
    if (b.points == 0) {
      EXPECT_EQ(boundary, 0.0);
      continue;
    }
    ++with_points;
    EXPECT_GT(b.pdf, 0.0);
    EXPECT_GT(b.rate, 0.0);
    EXPECT_GT(b.jump, 0.0);
    EXPECT_NE(b.jacobian, 0.0);
    EXPECT_GT(b.distance, 0.0);
    EXPECT_GE(b.segments, 1);
    EXPECT_GE(b.shape, 0);
  }
  EXPECT_GE(with_points, 8) << "the test needs samples with a boundary part";
}

INSTANTIATE_TEST_SUITE_P(LargestSamples, RetraceRecordsTheBoundaryTerm,
                         testing::Values(CameraHits::Detached, CameraHits::Adaptive));

TEST(LargestSamples, LargestFirstBoundEveryPixelAndIndependentOfThreads) {
  const DirectRun a = run_direct(Method::Quadric, 1), b = run_direct(Method::Quadric, 2);
  ASSERT_EQ(a.result.largest.size(), 8u);
  for (size_t i = 1; i < a.result.largest.size(); ++i)
    EXPECT_GE(std::abs(a.result.largest[i - 1].value), std::abs(a.result.largest[i].value));
  const Film& film = a.result.film;
  double largest_mean = 0;
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x)
      largest_mean = std::max(largest_mean, std::abs(film.mean(a.layout.derivative_mean(0), x, y)));
  EXPECT_GE(std::abs(a.result.largest[0].value), largest_mean);
  EXPECT_GT(largest_mean, 0.0);
  for (size_t i = 0; i < a.result.largest.size(); ++i) {
    const SampleTrace &s = a.result.largest[i], &t = b.result.largest[i];
    EXPECT_EQ(std::tie(s.x, s.y, s.sample, s.value), std::tie(t.x, t.y, t.sample, t.value));
  }
}

// Runs over disjoint sample ranges merge (RenderResult::merge) into the run over their union:
// the same samples, values and paths.
TEST(LargestSamples, MergedRangesKeepTheWholeRunsSamples) {
  static const Scene scene = load_scene(test::data_file("scenes/direct.xml"), {{"res", "16"}, {"spp", "16"}});
  const std::vector<ParameterSpec> params{parse_parameter("spot:translate:1,0,0", scene)};
  const Estimator e(scene, EstimatorConfig::gradient(params, Method::Quadric));
  auto run = [&](int first, int spp) {
    RenderOptions o;
    o.progress = false;
    o.seed = 3;
    o.first_sample = first;
    o.spp = spp;
    o.largest_samples = 8;
    return e.run(o);
  };
  RenderResult merged = run(0, 8);
  merged.merge(run(8, 8));
  const RenderResult whole = run(0, 16);
  ASSERT_EQ(merged.largest.size(), whole.largest.size());
  for (size_t i = 0; i < whole.largest.size(); ++i) {
    const SampleTrace &a = merged.largest[i], &b = whole.largest[i];
    EXPECT_EQ(std::tie(a.x, a.y, a.sample, a.value, a.interior), std::tie(b.x, b.y, b.sample, b.value, b.interior));
    EXPECT_EQ(a.vertices.size(), b.vertices.size());
  }
}

TEST(LargestSamples, NoneKeptWithoutTheOption) {
  EXPECT_TRUE(run_direct(Method::Quadric, 2, 0).result.largest.empty());
}

}  // namespace
}  // namespace qsil
