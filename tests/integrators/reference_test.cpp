// qsil::agreement (qsil/study/reference.h), the test behind `qsil agree` and the step study
// of tools/references.py, on synthetic references with known truth and Gaussian noise of known
// standard error: independent references agree; a 3 % scale error, a local bias that cancels in
// the image sum, or a differing exact block is refused; a blur of sharp lines is refused per pixel
// (not by blocks) and measured by excess_rel_mse. Fixed seeds; the agreeing case has
// chi^2/dof ~ 1 +- 0.1 against a limit of 1.76 (a false refusal has probability < 1e-9), the
// scaled one chi^2/dof ~ 3.9.
#include "qsil/study/reference.h"
#include "qsil/error.h"
#include "qsil/film.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace qsil {
namespace {

constexpr int kSize = 64;

/// truth(x, y) * scale + N(0, se^2) in dtheta0.R/G/B, se = 0.1, with .se channels; the pixels
/// of the top-left 8x8 block are exactly 0 with se 0 (a region no sample reached).
Reference synthetic(uint32_t seed, double scale) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Reference r;
  r.num_params = 1;
  r.image.width = r.image.height = kSize;
  for (int c = 0; c < 3; ++c) {
    const std::string name = FilmLayout::derivative_name(0, c);
    std::vector<float> v(kSize * kSize), se(kSize * kSize);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const size_t i = size_t(y) * kSize + x;
        if (x < 8 && y < 8) continue;
        const double truth = 1.0 + 0.5 * std::sin(0.1 * x + 0.2 * y + c);
        se[i] = 0.1f;
        v[i] = float(scale * truth + 0.1 * noise(rng));
      }
    r.image.channel_names.push_back(name);
    r.image.planes.push_back(v);
    r.image.channel_names.push_back(name + ".se");
    r.image.planes.push_back(se);
  }
  summarize_reference(r);
  return r;
}

TEST(Agreement, IndependentReferencesAgree) {
  const Agreement g = agreement(synthetic(1, 1.0), synthetic(2, 1.0), 8);
  EXPECT_EQ(g.tests, 63 * 3);  // 64 blocks x 3 channels, less the exact block
  EXPECT_EQ(g.unequal_exact, 0);
  EXPECT_NEAR(g.chi2_per_dof, 1.0, 0.4);
  EXPECT_TRUE(g.agrees()) << "chi2/dof " << g.chi2_per_dof << " sum z " << g.sum_z[0];
}

TEST(Agreement, ScaleErrorOfThreePercentIsRefused) {
  const Agreement g = agreement(synthetic(1, 1.0), synthetic(2, 1.03), 8);
  EXPECT_GT(g.chi2_per_dof, g.chi2_limit());
  EXPECT_GT(std::abs(g.sum_z[0]), 3);
  EXPECT_FALSE(g.agrees());
}

// A bias that cancels in the image sum (+0.1 on the left half, -0.1 on the right): only the block
// tests can see it (block z ~ 0.1 * 64 / 1.13 = 5.7 on every block, chi^2/dof ~ 33).
TEST(Agreement, LocalBiasWithUnchangedImageSumIsRefused) {
  Reference b = synthetic(2, 1.0);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x)
        if (!(x < 8 && y < 8)) b.image.at(2 * c, x, y) += x < kSize / 2 ? 0.1f : -0.1f;
  summarize_reference(b);
  const Agreement g = agreement(synthetic(1, 1.0), b, 8);
  EXPECT_LT(std::abs(g.sum_z[0]), 3);
  EXPECT_GT(g.chi2_per_dof, g.chi2_limit());
  EXPECT_FALSE(g.agrees());
}

// A finite-difference step whose silhouettes move about a pixel blurs the derivative image along
// the motion: sharp lines (a silhouette's pixels) spread to their neighbours, and block sums do not
// change. Here a line of value 4 at x = 3 (mod 8) in every row and its blur (1, 2, 1) / 4 inside
// the block: the 8x8 block test agrees (same block sums), the per-pixel test refuses (z ~ 14 on
// the line pixels), and excess_rel_mse finds the squared difference of the two truths (analytic,
// from the truths themselves) within 10 %, while for two independent references it stays within
// 5 standard deviations of 0 (its s.e. here is ~0.001).
TEST(Agreement, BlurOfSharpLinesIsSeenPerPixelAndMeasured) {
  Reference a = synthetic(1, 1.0), b = synthetic(2, 1.0);
  double diff2 = 0, mean2 = 0;
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        if (x < 8 && y < 8) continue;
        const int r = x % 8;
        const float line = r == 3 ? 4.0f : 0.0f, blurred = r == 3 ? 2.0f : (r == 2 || r == 4 ? 1.0f : 0.0f);
        a.image.at(2 * c, x, y) += line;
        b.image.at(2 * c, x, y) += blurred;
        const double truth = 1.0 + 0.5 * std::sin(0.1 * x + 0.2 * y + c);
        diff2 += double(line - blurred) * double(line - blurred);
        mean2 += std::pow(truth + 0.5 * (line + blurred), 2) + 0.25 * 2 * 0.01;  // E((a + b) / 2)^2
      }
  summarize_reference(a);
  summarize_reference(b);
  const Agreement blocks = agreement(a, b, 8), pixels = agreement(a, b, 1);
  EXPECT_TRUE(blocks.agrees()) << "chi2/dof " << blocks.chi2_per_dof;
  EXPECT_FALSE(pixels.agrees());
  EXPECT_GT(pixels.chi2_per_dof, 10 * pixels.chi2_limit());
  EXPECT_NEAR(pixels.excess_rel_mse, diff2 / mean2, 0.1 * diff2 / mean2);
  EXPECT_NEAR(blocks.excess_rel_mse, pixels.excess_rel_mse, 1e-9);  // per pixel whatever the block
  const Agreement independent = agreement(synthetic(1, 1.0), synthetic(2, 1.0), 1);
  EXPECT_NEAR(independent.excess_rel_mse, 0.0, 0.005);
  EXPECT_GT(pixels.excess_rel_mse, 10 * pixels.excess_se);  // the blur is resolved
  EXPECT_GT(independent.noise_rel_mse, 0.0);
}

// excess_se is the spread of excess_rel_mse over independent pairs: over 400 pairs of independent
// references (fixed seeds), the sample standard deviation of excess_rel_mse is within 20 % of the
// mean excess_se (the sample s.d. of 400 draws has a relative s.d. of ~3.5 %; the ratio is 0.93
// here, 0.77 over the first 100 pairs), and every |excess| is below 4 s.e. An excess_se 0.6x or
// 1.4x its value leaves the band (mutation 0.6x: ratio 1.55, refused).
TEST(Agreement, ExcessStandardErrorMatchesItsSpreadOverIndependentPairs) {
  constexpr int kPairs = 400;
  double sum = 0, sum2 = 0, se_sum = 0;
  for (int i = 0; i < kPairs; ++i) {
    const Agreement g = agreement(synthetic(uint32_t(100 + 2 * i), 1.0), synthetic(uint32_t(101 + 2 * i), 1.0), 1);
    ASSERT_GT(g.excess_se, 0.0);
    EXPECT_LT(std::abs(g.excess_rel_mse), 4 * g.excess_se) << "pair " << i;
    sum += g.excess_rel_mse;
    sum2 += g.excess_rel_mse * g.excess_rel_mse;
    se_sum += g.excess_se;
  }
  const double mean = sum / kPairs, sd = std::sqrt((sum2 - kPairs * mean * mean) / (kPairs - 1));
  const double se_mean = se_sum / kPairs;
  EXPECT_NEAR(sd / se_mean, 1.0, 0.2) << "spread " << sd << " vs s.e. " << se_mean;
}

TEST(Agreement, UnequalZeroVarianceBlockIsRefused) {
  Reference b = synthetic(2, 1.0);
  b.image.at(0, 3, 3) = 0.5f;  // dtheta0.R in the exact block, still with se 0
  summarize_reference(b);
  const Agreement g = agreement(synthetic(1, 1.0), b, 8);
  EXPECT_EQ(g.unequal_exact, 1);
  EXPECT_FALSE(g.agrees());
}

// A block one reference never sampled (every pixel 0 with s.e. 0, as finite differences leave a
// rare event's region) against a precise small value of the other (0.001 per pixel, s.e. 1e-5:
// block z = 0.064 / 8e-5 = 800 per channel): the three tests are counted as unseen, and chi²/dof
// without them is the independent references' (~1), while agrees() still refuses.
TEST(Agreement, BlocksOneReferenceNeverSampledAreCounted) {
  Reference a = synthetic(1, 1.0), b = synthetic(2, 1.0);
  for (int c = 0; c < 3; ++c)
    for (int y = 8; y < 16; ++y)
      for (int x = 0; x < 8; ++x) {
        a.image.at(2 * c, x, y) = 0.001f;
        a.image.at(2 * c + 1, x, y) = 1e-5f;
        b.image.at(2 * c, x, y) = 0.0f;
        b.image.at(2 * c + 1, x, y) = 0.0f;
      }
  summarize_reference(a);
  summarize_reference(b);
  const Agreement g = agreement(a, b, 8);
  EXPECT_EQ(g.unseen, 3);
  EXPECT_EQ(g.tests, 63 * 3);
  EXPECT_GT(g.chi2_per_dof, 100.0);
  EXPECT_NEAR(g.chi2_per_dof_seen, 1.0, 0.4);
  EXPECT_FALSE(g.agrees());
  EXPECT_EQ(agreement(synthetic(1, 1.0), synthetic(2, 1.0), 8).unseen, 0);
}

TEST(Agreement, RefusesDifferentSizesAndBadBlocks) {
  Reference small = synthetic(1, 1.0);
  small.image.width = 32;
  EXPECT_THROW(agreement(synthetic(1, 1.0), small, 8), Error);
  EXPECT_THROW(agreement(synthetic(1, 1.0), synthetic(2, 1.0), 0), Error);
}

}  // namespace
}  // namespace qsil
