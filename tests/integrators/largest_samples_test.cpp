// RenderOptions::largest_samples (qsil/integrators/sample_trace.h): the samples of largest
// |derivative| of a gradient run and their retraced paths.
// - Replay: with no boundary term (Method::None) a sample is its interior term, and the retrace
//   from the sample's own stream must reproduce it exactly (a retrace from the wrong stream, or a
//   path that differs, fails this); with the quadric boundary term the interior part is the same
//   sample retraced, so it equals the None run's value of that sample.
// - Bookkeeping: the camera's emission plus what each vertex adds is the interior term.
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

TEST(LargestSamples, RetraceReproducesTheInteriorTerm) {
  const DirectRun none = run_direct(Method::None, 2);
  ASSERT_EQ(none.result.largest.size(), 8u);
  for (const SampleTrace& s : none.result.largest) {
    EXPECT_EQ(s.interior, s.value) << "pixel (" << s.x << ", " << s.y << ") sample " << s.sample;
    ASSERT_FALSE(s.vertices.empty());
    double sum = s.camera_emission;
    for (const VertexTrace& v : s.vertices) sum += v.added;
    EXPECT_NEAR(sum, s.interior, 1e-12 * std::abs(s.interior)) << "the vertices' parts sum to the interior term";
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
