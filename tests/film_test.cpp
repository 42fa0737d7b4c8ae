// The film layout (qsil/film.h): channel indices, names, hidden channels and standard-error
// channels, and the film's merge and image sums; the standard error of a pixel whose samples come
// in two strata of different means (every other sample shifted by 10, as an estimator that makes
// one more boundary traversal every other sample), checked against the spread of the pixel's mean
// over 2000 independent pixels (within 5 %; the pooled estimate is 5x too large there); and the
// state round trip with strata.
#include "qsil/film.h"
#include "qsil/rng.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace qsil {
namespace {

TEST(FilmLayout, ChannelIndicesAreDistinctAndInRange) {
  for (int K = 0; K <= 8; ++K) {
    const FilmLayout layout(K);
    EXPECT_EQ(layout.channels(), 3 * (1 + K) + K);
    EXPECT_EQ(layout.image_channels(), 3 * (1 + K));
    std::set<int> used;
    for (int c = 0; c < 3; ++c) used.insert(layout.primal(c));
    for (int k = 0; k < K; ++k) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_LT(layout.derivative(k, c), layout.image_channels());
        used.insert(layout.derivative(k, c));
      }
      EXPECT_GE(layout.derivative_mean(k), layout.image_channels());  // hidden
      used.insert(layout.derivative_mean(k));
    }
    EXPECT_EQ(int(used.size()), layout.channels()) << K;
    EXPECT_EQ(*used.rbegin(), layout.channels() - 1);
  }
}

TEST(FilmLayout, NamesMatchIndices) {
  const FilmLayout layout(2);
  const auto names = layout.names();
  ASSERT_EQ(int(names.size()), layout.image_channels());
  EXPECT_EQ(names[size_t(layout.primal(1))], "G");
  EXPECT_EQ(names[size_t(layout.derivative(1, 2))], "dtheta1.B");
  EXPECT_EQ(FilmLayout::derivative_name(1, 2), "dtheta1.B");
  EXPECT_EQ(FilmLayout::derivative_prefix(0), "dtheta0");
  const auto se = layout.standard_error_names();
  ASSERT_EQ(se.size(), names.size());
  EXPECT_EQ(se[size_t(layout.derivative(0, 0))], "dtheta0.R.se");
}

TEST(Film, ImagesMergeAndSums) {
  const FilmLayout layout(1);
  Film a(2, 1, layout), b(2, 1, layout);
  std::vector<double> v(size_t(layout.channels()), 0.0);
  for (int s = 0; s < 4; ++s) {
    for (int x = 0; x < 2; ++x) {
      for (int c = 0; c < 3; ++c) v[size_t(layout.derivative(0, c))] = s + x + c;
      v[size_t(layout.derivative_mean(0))] = s + x + 1;  // the mean of the three
      (s < 2 ? a : b).add_sample(x, 0, v.data());
    }
  }
  a.merge(b);
  EXPECT_EQ(a.samples(0, 0), 4);
  EXPECT_DOUBLE_EQ(a.mean(layout.derivative(0, 2), 1, 0), (1 + 2 + 3 + 4) / 4.0 + 2);
  const ImageSum sum = a.derivative_sum(0);
  EXPECT_DOUBLE_EQ(sum.sum, 2.5 + 3.5);
  EXPECT_GT(sum.standard_error, 0);
  const Image img = a.to_image_with_standard_errors();
  EXPECT_EQ(int(img.channel_names.size()), 2 * layout.image_channels());
  EXPECT_GE(img.channel_index("dtheta0.G.se"), layout.image_channels());
  EXPECT_FLOAT_EQ(img.at(img.channel_index("dtheta0.B"), 1, 0), float((1 + 2 + 3 + 4) / 4.0 + 2));
}

TEST(Film, StandardErrorWeighsEachStratumsOwnVariance) {
  const FilmLayout layout(0);
  const int pixels = 2000, n = 16;
  Film film(pixels, 1, layout, /*stratified=*/true), pooled(pixels, 1, layout);
  std::vector<double> v(size_t(layout.channels()), 0.0);
  Sampler rng(1, 2, 3);
  for (int x = 0; x < pixels; ++x)
    for (int s = 0; s < n; ++s) {
      // Uniform noise of variance 1 (sqrt 12 (u - 1/2)) plus 10 in stratum 1.
      v[0] = std::sqrt(12.0) * (rng.next() - 0.5) + (s % 2 ? 10.0 : 0.0);
      film.add_sample(x, 0, v.data(), s % 2);
      pooled.add_sample(x, 0, v.data());
    }
  // The spread of the pixels' means (all pixels alike): sqrt(1 / n) for the stratified sampling.
  double m = 0, m2 = 0, se2 = 0, pooled_se2 = 0;
  for (int x = 0; x < pixels; ++x) {
    m += film.mean(0, x, 0);
    m2 += film.mean(0, x, 0) * film.mean(0, x, 0);
    se2 += std::pow(film.standard_error(0, x, 0), 2);
    pooled_se2 += std::pow(pooled.standard_error(0, x, 0), 2);
  }
  m /= pixels;
  const double spread2 = (m2 / pixels - m * m) * pixels / (pixels - 1);
  EXPECT_NEAR(spread2, 1.0 / n, 0.1 / n);  // the sampling (2000 pixels: ~3 % s.e.)
  EXPECT_NEAR(se2 / pixels, spread2, 0.05 * spread2) << "the stratified standard error";
  EXPECT_GT(pooled_se2 / pixels, 20 * spread2) << "the pooled one over-estimates it (26 / n)";
  // The state round trip keeps the strata.
  Film copy(pixels, 1, layout, true);
  copy.set_state(film.state());
  EXPECT_EQ(copy.standard_error(0, 7, 0), film.standard_error(0, 7, 0));
  EXPECT_EQ(film.state_size(), film.state().size());
}

}  // namespace
}  // namespace qsil
