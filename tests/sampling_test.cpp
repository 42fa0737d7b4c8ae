/// @file sampling_test.cpp
/// Tests of the warps and of Distribution1D/2D (include/qsil/sampling.h).
/// Statistical tests: fixed seeds; chi-square at a family-wise significance of 1% over the
/// chi-square tests of this file (Šidák-corrected per test), pooling cells with expected < 5.

#include "qsil/sampling.h"

#include "chi2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <vector>

namespace qsil {
namespace {

using test::chi2_test;
using test::sidak;
using test::SphereBins;
using test::TestRng;

/// Number of chi-square tests in this file (for the Šidák correction).
constexpr int kChi2Tests = 6;
const double kSignificance = sidak(0.01, kChi2Tests);

// ---------------------------------------------------------------------------------------------
// Warps
// ---------------------------------------------------------------------------------------------

/// Chi-square of a direction warp against its analytic density integrated per (cos, phi) bin;
/// `bin_integral(c0, c1)` is the integral of the density over cos theta in [c0,c1] for all phi.
template <class Warp, class BinIntegral>
test::Chi2Result chi2_direction_warp(Warp warp, BinIntegral bin_integral, uint64_t seed) {
  const SphereBins bins{20, 40};
  const int n = 400000;
  std::vector<double> obs(size_t(bins.count()), 0.0), exp(size_t(bins.count()), 0.0);
  TestRng rng(seed);
  for (int i = 0; i < n; ++i) obs[size_t(bins.index(warp(rng.uniform2())))] += 1;
  for (int ic = 0; ic < bins.n_cos; ++ic) {
    const double c0 = -1.0 + 2.0 * ic / bins.n_cos, c1 = -1.0 + 2.0 * (ic + 1) / bins.n_cos;
    for (int ip = 0; ip < bins.n_phi; ++ip) exp[size_t(ic * bins.n_phi + ip)] = n * bin_integral(c0, c1) / bins.n_phi;
  }
  return chi2_test(obs, exp, kSignificance);
}

TEST(SamplingWarps, UniformSphereChi2) {
  const auto r = chi2_direction_warp(
      square_to_uniform_sphere, [](double c0, double c1) { return (c1 - c0) * 2 * kPi * uniform_sphere_pdf(); }, 1);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(SamplingWarps, UniformHemisphereChi2) {
  const auto r = chi2_direction_warp(
      square_to_uniform_hemisphere,
      [](double c0, double c1) { return c0 >= 0 ? (c1 - c0) * 2 * kPi * uniform_hemisphere_pdf(0.5) : 0.0; }, 2);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(SamplingWarps, CosineHemisphereChi2) {
  // integral of cos/pi over cos in [c0,c1] and all phi: (c1^2 - c0^2) (2 pi) / (2 pi).
  const auto r = chi2_direction_warp(
      square_to_cosine_hemisphere, [](double c0, double c1) { return c0 >= 0 ? (c1 * c1 - c0 * c0) : 0.0; }, 3);
  EXPECT_TRUE(r.passed) << r.message;
  // The pdf helper agrees with the normalised density, and the directions are unit.
  TestRng rng(4);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 d = square_to_cosine_hemisphere(rng.uniform2());
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    EXPECT_GE(d.z(), 0.0);
    EXPECT_DOUBLE_EQ(cosine_hemisphere_pdf(d.z()), d.z() / kPi);
  }
}

TEST(SamplingWarps, CosineHemisphereChi2DetectsWrongDensity) {
  // Negative control: the uniform hemisphere warp tested against the cosine density must fail.
  const auto r = chi2_direction_warp(
      square_to_uniform_hemisphere, [](double c0, double c1) { return c0 >= 0 ? (c1 * c1 - c0 * c0) : 0.0; }, 5);
  EXPECT_FALSE(r.passed) << r.message;
}

TEST(SamplingWarps, UniformTriangleChi2) {
  // Triangle (0,0), (1,0), (0,1): the point is (b1, b2). Cells of an n x n grid over the unit
  // square are fully inside (i + j < n - 1), half inside (i + j = n - 1, cut by the diagonal
  // exactly), or outside; the expected count is 2 N x (area inside).
  const int n = 30, samples = 400000;
  const double h = 1.0 / n;
  std::vector<double> obs(size_t(n * n), 0.0), exp(size_t(n * n), 0.0);
  TestRng rng(6);
  for (int s = 0; s < samples; ++s) {
    const Vec3 b = square_to_uniform_triangle(rng.uniform2());
    ASSERT_NEAR(b.sum(), 1.0, 1e-15);
    ASSERT_TRUE(b.minCoeff() >= 0.0);
    const int i = std::min(int(b[1] / h), n - 1), j = std::min(int(b[2] / h), n - 1);
    obs[size_t(i * n + j)] += 1;
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      exp[size_t(i * n + j)] = 2.0 * samples * (i + j < n - 1 ? h * h : i + j == n - 1 ? 0.5 * h * h : 0.0);
  const auto r = chi2_test(obs, exp, kSignificance);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(SamplingWarps, ConcentricDiskIsInsideAndCentred) {
  EXPECT_EQ(square_to_concentric_disk(Vec2(0.5, 0.5)), Vec2::Zero());
  TestRng rng(7);
  for (int i = 0; i < 10000; ++i) EXPECT_LE(square_to_concentric_disk(rng.uniform2()).norm(), 1.0 + 1e-15);
  // Corners of the square map to the unit circle.
  EXPECT_NEAR(square_to_concentric_disk(Vec2(1.0, 1.0)).norm(), 1.0, 1e-15);
  EXPECT_NEAR(square_to_concentric_disk(Vec2(0.0, 0.5)).norm(), 1.0, 1e-15);
}

// ---------------------------------------------------------------------------------------------
// Distribution1D
// ---------------------------------------------------------------------------------------------

/// Weights with zero bins at both ends and between non-zero ones.
const std::vector<double> kGappy = {0.0, 1.0, 0.0, 0.0, 3.0, 0.0, 2.0, 1e-3, 0.0, 0.0};

TEST(SamplingDistribution1D, PmfPdfAndIntegral) {
  const Distribution1D d(kGappy);
  const double sum = 6.001;
  EXPECT_EQ(d.size(), 10);
  EXPECT_NEAR(d.integral(), sum / 10, 1e-15);
  for (int i = 0; i < d.size(); ++i) {
    EXPECT_NEAR(d.pmf(i), kGappy[size_t(i)] / sum, 1e-15);
    EXPECT_NEAR(d.pdf((i + 0.5) / 10), kGappy[size_t(i)] / (sum / 10), 1e-12);
  }
  EXPECT_EQ(d.cdf().front(), 0.0);
  EXPECT_EQ(d.cdf().back(), 1.0);
  EXPECT_EQ(d.pdf(-0.1), 0.0);
  EXPECT_EQ(d.pdf(1.0), 0.0);
}

TEST(SamplingDistribution1D, GuideTableFindsTheSameBinAsABinarySearch) {
  // Weights spanning nine decades (every bin positive), so the guide table's intervals hold from
  // one to hundreds of bins; u at random, at every CDF value and k/n and one ulp either side.
  TestRng rng(11);
  std::vector<double> w(1000);
  for (double& x : w) x = std::pow(10.0, -9.0 * rng.uniform());
  const Distribution1D d(w);
  std::vector<double> us;
  for (int i = 0; i < 20000; ++i) us.push_back(rng.uniform());
  const std::vector<double> cdf = d.cdf();
  for (double c : cdf) us.insert(us.end(), {c, std::nextafter(c, 0.0), std::nextafter(c, 2.0)});
  for (int k = 0; k <= d.size(); ++k) {
    const double c = double(k) / d.size();
    us.insert(us.end(), {c, std::nextafter(c, 0.0), std::nextafter(c, 2.0)});
  }
  for (double u : us) {
    const double uc = std::clamp(u, 0.0, std::nextafter(1.0, 0.0));
    const int expected =
        std::clamp(int(std::upper_bound(cdf.begin(), cdf.end(), uc) - cdf.begin()) - 1, 0, d.size() - 1);
    ASSERT_EQ(d.sample(u).index, expected) << "u = " << u;
  }
}

TEST(SamplingDistribution1D, NeverReturnsZeroProbabilityBin) {
  const Distribution1D d(kGappy);
  // u at every CDF value, one ulp either side, and the extremes, including 1 - epsilon, 1 and
  // beyond (clamped): exactly the values where rounding would land on a zero-width bin.
  std::vector<double> us = {0.0, std::nextafter(0.0, 1.0), 1.0 - 1e-16, std::nextafter(1.0, 0.0), 1.0, 1.5, -0.5};
  for (double c : d.cdf()) {
    us.push_back(c);
    us.push_back(std::nextafter(c, 0.0));
    us.push_back(std::nextafter(c, 2.0));
  }
  for (double u : us) {
    const auto s = d.sample(u);
    SCOPED_TRACE(testing::Message() << "u = " << u);
    ASSERT_GT(kGappy[size_t(s.index)], 0.0);
    ASSERT_GT(s.pdf, 0.0);
    ASSERT_GE(s.x, 0.0);
    ASSERT_LT(s.x, 1.0);
    ASSERT_EQ(int(s.x * d.size()), s.index) << "x outside its bin";
    ASSERT_EQ(d.pdf(s.x), s.pdf);
    const auto sd = d.sample_discrete(u);
    ASSERT_EQ(sd.index, s.index);
    ASSERT_GE(sd.x, 0.0);
    ASSERT_LT(sd.x, 1.0);
  }
  // A weight so small that its CDF width rounds to zero is never chosen either; a trailing run
  // of zeros with u = 1 - epsilon lands on the last non-zero bin.
  const Distribution1D tail(std::vector<double>{1.0, 1e-30, 0.0, 0.0});
  for (double u : {std::nextafter(1.0, 0.0), 1.0}) {
    const auto s = tail.sample(u);
    EXPECT_GT(tail.weight(s.index), 0.0);
  }
}

TEST(SamplingDistribution1D, SampleMatchesPdfChi2) {
  // Histogram of x over 4 sub-bins per bin against the piecewise-constant density.
  const Distribution1D d(kGappy);
  const int sub = 4, nb = d.size() * sub, n = 200000;
  std::vector<double> obs(size_t(nb), 0.0), exp(size_t(nb), 0.0);
  TestRng rng(11);
  for (int i = 0; i < n; ++i) {
    const auto s = d.sample(rng.uniform());
    ASSERT_EQ(s.pdf, d.pdf(s.x));
    obs[size_t(std::min(int(s.x * nb), nb - 1))] += 1;
  }
  for (int b = 0; b < nb; ++b) exp[size_t(b)] = n * d.pdf((b + 0.5) / nb) / nb;
  const auto r = chi2_test(obs, exp, kSignificance);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(SamplingDistribution1D, AllZeroIsExplicitlyDegenerate) {
  const Distribution1D d(std::vector<double>{0.0, 0.0, 0.0});
  EXPECT_TRUE(d.is_zero());
  EXPECT_EQ(d.integral(), 0.0);
  for (double u : {0.0, 0.3, std::nextafter(1.0, 0.0)}) {
    const auto s = d.sample(u);
    EXPECT_EQ(s.pdf, 0.0);  // invalid: nothing to sample
    EXPECT_EQ(s.pmf, 0.0);
    EXPECT_TRUE(s.x >= 0.0 && s.x < 1.0);
    EXPECT_TRUE(s.index >= 0 && s.index < 3);
  }
  EXPECT_EQ(d.pdf(0.5), 0.0);
  EXPECT_EQ(d.pmf(1), 0.0);
}

TEST(SamplingDistribution1D, RejectsInvalidWeights) {
  EXPECT_THROW(Distribution1D(std::vector<double>{1.0, -1.0}), std::invalid_argument);
  EXPECT_THROW(Distribution1D(std::vector<double>{1.0, std::nan("")}), std::invalid_argument);
  EXPECT_THROW(Distribution1D(std::vector<double>{}), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Distribution2D
// ---------------------------------------------------------------------------------------------

/// 5 columns x 4 rows with a zero row, a zero column and isolated zeros.
const std::vector<double> kGrid = {0.0, 1.0, 0.0, 2.0, 0.5,   // row 0
                                   0.0, 0.0, 0.0, 0.0, 0.0,   // row 1: all zero
                                   0.0, 4.0, 1.0, 0.0, 0.25,  // row 2
                                   0.0, 0.0, 3.0, 1.0, 0.0};  // row 3

TEST(SamplingDistribution2D, NeverReturnsZeroCellAndPdfMatches) {
  const Distribution2D d(kGrid, 5, 4);
  EXPECT_NEAR(d.integral(), 12.75 / 20, 1e-15);
  const std::vector<double> edges = {0.0, 1e-17, 0.2, 0.25, 0.5, 0.75, 0.8, 1.0 - 1e-16, std::nextafter(1.0, 0.0)};
  for (double ux : edges)
    for (double uy : edges) {
      const auto s = d.sample(Vec2(ux, uy));
      SCOPED_TRACE(testing::Message() << "u = (" << ux << ", " << uy << ")");
      ASSERT_GT(kGrid[size_t(s.iv * 5 + s.iu)], 0.0);
      ASSERT_EQ(int(s.p.x() * 5), s.iu);
      ASSERT_EQ(int(s.p.y() * 4), s.iv);
      ASSERT_NEAR(d.pdf(s.p), s.pdf, 1e-12 * s.pdf);
    }
}

TEST(SamplingDistribution2D, SampleMatchesPdfChi2) {
  const Distribution2D d(kGrid, 5, 4);
  // Cells of 2 x 2 sub-cells each; the expected count is the (constant) pdf times the area.
  const int nu = 10, nv = 8, n = 200000;
  std::vector<double> obs(size_t(nu * nv), 0.0), exp(size_t(nu * nv), 0.0);
  TestRng rng(12);
  double pdf_integral = 0;
  for (int i = 0; i < n; ++i) {
    const auto s = d.sample(rng.uniform2());
    obs[size_t(std::min(int(s.p.y() * nv), nv - 1) * nu + std::min(int(s.p.x() * nu), nu - 1))] += 1;
  }
  for (int y = 0; y < nv; ++y)
    for (int x = 0; x < nu; ++x) {
      const double p = d.pdf(Vec2((x + 0.5) / nu, (y + 0.5) / nv)) / (nu * nv);
      exp[size_t(y * nu + x)] = n * p;
      pdf_integral += p;
    }
  EXPECT_NEAR(pdf_integral, 1.0, 1e-12);
  const auto r = chi2_test(obs, exp, kSignificance);
  EXPECT_TRUE(r.passed) << r.message;
}

// The rows live in one array (Distribution2D's layout) but must sample as a Distribution1D of
// their weights does, and the rows' integrals must weigh the marginal: the same cell, position
// and density, bit for bit, as the marginal-then-conditional composition of 1D distributions.
TEST(SamplingDistribution2D, RowsSampleAsTheirDistribution1D) {
  const int nu = 7, nv = 6;
  TestRng rng(31);
  std::vector<double> f(size_t(nu * nv));
  for (size_t i = 0; i < f.size(); ++i) f[i] = i % 5 == 1 ? 0.0 : rng.uniform() * (1 + int(i) % 3);
  for (int x = 0; x < nu; ++x) f[size_t(2 * nu + x)] = 0.0;  // a row of zero weight
  const Distribution2D d(f, nu, nv);
  std::vector<Distribution1D> rows;
  std::vector<double> integrals;
  for (int v = 0; v < nv; ++v) {
    rows.emplace_back(std::span<const double>(f).subspan(size_t(v * nu), size_t(nu)));
    integrals.push_back(rows.back().integral());
  }
  const Distribution1D marginal(integrals);
  EXPECT_EQ(d.integral(), marginal.integral());
  std::vector<Vec2> us = {Vec2(0, 0), Vec2(std::nextafter(1.0, 0.0), std::nextafter(1.0, 0.0)), Vec2(0.5, 1.0 / 3)};
  for (int i = 0; i < 2000; ++i) us.push_back(rng.uniform2());
  for (const Vec2& u : us) {
    const auto s = d.sample(u);
    const auto row = marginal.sample(u.y());
    const auto col = rows[size_t(row.index)].sample(u.x());
    ASSERT_EQ(s.iv, row.index);
    ASSERT_EQ(s.iu, col.index);
    ASSERT_EQ(s.p, Vec2(col.x, row.x));
    ASSERT_EQ(s.pdf, row.pdf * col.pdf);
    ASSERT_EQ(d.pdf(s.p), rows[size_t(s.iv)].weight(s.iu) / marginal.integral());
  }
}

TEST(SamplingDistribution2D, AllZeroIsDegenerate) {
  const std::vector<double> zeros(6, 0.0);
  const Distribution2D d(zeros, 3, 2);
  EXPECT_TRUE(d.is_zero());
  EXPECT_EQ(d.sample(Vec2(0.5, 0.5)).pdf, 0.0);
  EXPECT_EQ(d.pdf(Vec2(0.5, 0.5)), 0.0);
  EXPECT_THROW(Distribution2D(zeros, 4, 2), std::invalid_argument);
}

}  // namespace
}  // namespace qsil
