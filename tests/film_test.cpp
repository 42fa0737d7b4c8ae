// The film layout (qsil/film.h): channel indices, names, hidden channels and standard-error
// channels, and the film's merge and image sums; the standard error of a pixel whose samples come
// in two strata of different means (the samples a stratified pick selects shifted by 10, as an
// estimator that makes one more boundary traversal on them), checked against the spread of the
// pixel's mean over 4000 independent pixels (within 6 %, about 3 standard errors of that spread;
// the pooled estimate is 5x too large there), for a whole count of picks (16 samples at 1/2) and a
// varying one (15 samples at 0.3: 4 or 5 picks); and the state round trip with strata.
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

/// ImageSum::largest_share and its pixel against brute force over the film's own standard errors
/// (the oracle), on unit noise (no pixel dominates: the share is near 1 / pixels) and with one
/// sample of 10^4 among 64 in pixel (5, 9) (it holds nearly all of the variance).
TEST(Film, LargestShareOfTheImageSumsVarianceIsTheDominantPixels) {
  const FilmLayout layout(1);
  const int w = 16, h = 12, n = 64;
  for (const bool huge : {false, true}) {
    Film film(w, h, layout);
    std::vector<double> v(size_t(layout.channels()), 0.0);
    Sampler rng(5, 6, 7);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int s = 0; s < n; ++s) {
          double d = std::sqrt(12.0) * (rng.next() - 0.5);
          if (huge && x == 5 && y == 9 && s == 17) d = 1e4;
          for (int c = 0; c < 3; ++c) v[size_t(layout.derivative(0, c))] = d;
          v[size_t(layout.derivative_mean(0))] = d;
          film.add_sample(x, y, v.data());
        }
    double var = 0, largest = 0;
    int lx = -1, ly = -1;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double se2 = std::pow(film.standard_error(layout.derivative_mean(0), x, y), 2);
        var += se2;
        if (se2 > largest) largest = se2, lx = x, ly = y;
      }
    const ImageSum sum = film.derivative_sum(0);
    EXPECT_NEAR(sum.largest_share, largest / var, 1e-12) << huge;
    EXPECT_EQ(sum.largest_x, lx) << huge;
    EXPECT_EQ(sum.largest_y, ly) << huge;
    EXPECT_GE(sum.largest_share, 1.0 / (w * h));  // the largest share is at least the mean share
    if (huge) {
      EXPECT_EQ(sum.largest_x, 5);
      EXPECT_EQ(sum.largest_y, 9);
      EXPECT_GT(sum.largest_share, 0.999);
      EXPECT_GE(sum.largest_share, kDominantPixelShare);
    } else {
      EXPECT_LT(sum.largest_share, 2.0 / (w * h));  // 64 samples: a pixel's variance within ~±50 %
    }
  }
  // A film without samples has no variance and no such pixel.
  const ImageSum empty = Film(4, 4, layout).derivative_sum(0);
  EXPECT_EQ(empty.largest_share, 0.0);
  EXPECT_EQ(empty.largest_x, -1);
}

/// has_dominant_pixel: at a share of exactly kDominantPixelShare (two pixels of equal variance) and
/// above, on films of two or more pixels; never on a one-pixel film, whose share is always 1; not
/// at a third (three equal pixels).
TEST(Film, DominantPixelIsAtLeastHalfTheVarianceOnAFilmOfTwoOrMorePixels) {
  const FilmLayout layout(1);
  auto film_of = [&](int w) {
    Film film(w, 1, layout);
    std::vector<double> v(size_t(layout.channels()), 0.0);
    for (int x = 0; x < w; ++x)
      for (const double d : {1.0, -1.0, 3.0}) {  // the same samples in every pixel: equal variances
        v[size_t(layout.derivative_mean(0))] = d;
        film.add_sample(x, 0, v.data());
      }
    return film;
  };
  const Film one = film_of(1), two = film_of(2), three = film_of(3);
  EXPECT_EQ(one.derivative_sum(0).largest_share, 1.0);
  EXPECT_FALSE(has_dominant_pixel(one.derivative_sum(0), one));
  EXPECT_EQ(two.derivative_sum(0).largest_share, 0.5);
  EXPECT_TRUE(has_dominant_pixel(two.derivative_sum(0), two));
  EXPECT_NEAR(three.derivative_sum(0).largest_share, 1.0 / 3.0, 1e-15);
  EXPECT_FALSE(has_dominant_pixel(three.derivative_sum(0), three));
  const std::string text = dominant_pixel_warning(two.derivative_sum(0), 0);
  EXPECT_EQ(text.rfind("dtheta0: pixel (0, 0) holds 50 % of the image sum's variance", 0), 0u) << text;
  // A sample whose square overflows: that pixel's squared standard error is infinite, and it holds
  // the whole variance (not NaN, which no threshold would catch).
  Film overflow = film_of(3);
  std::vector<double> v(size_t(layout.channels()), 0.0);
  v[size_t(layout.derivative_mean(0))] = 1e200;
  overflow.add_sample(1, 0, v.data());
  const ImageSum big = overflow.derivative_sum(0);
  EXPECT_EQ(big.largest_x, 1);
  EXPECT_EQ(big.largest_share, 1.0);
  EXPECT_TRUE(has_dominant_pixel(big, overflow));
}

/// The spread of 4000 pixel means and the mean squared standard errors of the stratified and the
/// pooled film, for n samples per pixel of unit-variance noise, those a stratified pick of
/// fraction f selects (a rotation phi per pixel) shifted by 10.
struct StrataCase {
  double spread2 = 0, se2 = 0, pooled_se2 = 0;
};
StrataCase strata_case(int n, double f) {
  const FilmLayout layout(0);
  const int pixels = 4000;
  Film film(pixels, 1, layout, f), pooled(pixels, 1, layout);
  std::vector<double> v(size_t(layout.channels()), 0.0);
  Sampler rng(1, 2, 3);
  for (int x = 0; x < pixels; ++x) {
    const double phi = rng.next();
    for (int s = 0; s < n; ++s) {
      const int picked = int(std::floor(f * (s + 1) + phi) - std::floor(f * s + phi));
      // Uniform noise of variance 1 (sqrt 12 (u - 1/2)), plus 10 where picked.
      v[0] = std::sqrt(12.0) * (rng.next() - 0.5) + 10.0 * picked;
      film.add_sample(x, 0, v.data(), picked);
      pooled.add_sample(x, 0, v.data());
    }
  }
  StrataCase c;
  double m = 0, m2 = 0;
  for (int x = 0; x < pixels; ++x) {
    m += film.mean(0, x, 0);
    m2 += film.mean(0, x, 0) * film.mean(0, x, 0);
    c.se2 += std::pow(film.standard_error(0, x, 0), 2) / pixels;
    c.pooled_se2 += std::pow(pooled.standard_error(0, x, 0), 2) / pixels;
  }
  m /= pixels;
  c.spread2 = (m2 / pixels - m * m) * pixels / (pixels - 1);
  // The state round trip keeps the strata.
  Film copy(pixels, 1, layout, f);
  copy.set_state(film.state());
  EXPECT_EQ(copy.standard_error(0, 7, 0), film.standard_error(0, 7, 0));
  EXPECT_EQ(film.state_size(), film.state().size());
  return c;
}

TEST(Film, StandardErrorWeighsEachStratumsOwnVariance) {
  // 16 samples at 1/2: 8 picks in every pixel, the mean's variance 1/16.
  const StrataCase whole = strata_case(16, 0.5);
  EXPECT_NEAR(whole.spread2, 1.0 / 16, 0.1 / 16);
  EXPECT_NEAR(whole.se2, whole.spread2, 0.06 * whole.spread2) << "the stratified standard error";
  EXPECT_GT(whole.pooled_se2, 20 * whole.spread2) << "the pooled one over-estimates it (26 / n)";
  // 15 samples at 0.3: 4 or 5 picks (probabilities 0.5 each), which adds 0.25 x 10² / 15² = 0.111
  // to the mean's variance 1/15 = 0.067.
  const StrataCase varying = strata_case(15, 0.3);
  EXPECT_NEAR(varying.spread2, 1.0 / 15 + 25.0 / 225, 0.1 * varying.spread2);
  EXPECT_NEAR(varying.se2, varying.spread2, 0.06 * varying.spread2) << "with the variance of the pick's count";
}

}  // namespace
}  // namespace qsil
