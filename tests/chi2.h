#pragma once
/// @file chi2.h
/// Test helpers for statistical tests of sampling routines (docs/architecture.md §9):
/// - Pearson's chi-square goodness-of-fit test with pooling of low-expected cells, as in
///   Mitsuba 3's `python/mitsuba/chi2.py` (ChiSquareTest) and pbrt-v4's `bsdfs_test.cpp`;
/// - the chi-square survival function (regularized upper incomplete gamma, Numerical Recipes
///   §6.2), since the test binary has no statistics library;
/// - Šidák correction for running several tests at one family-wise significance;
/// - a spherical quadrature concentrated around a chosen direction (for very peaked densities
///   such as GGX at alpha = 0.01) and (cos theta, phi) binning of directions.

#include "qsil/math.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

namespace qsil::test {

/// A small deterministic generator for tests (SplitMix64, Steele et al. 2014): the same numbers
/// on every platform and standard library, independent of the renderer's PCG streams.
struct TestRng {
  uint64_t state;
  explicit TestRng(uint64_t seed) : state(seed) {}
  uint64_t next_u64() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0,1) with 53 random bits.
  double uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }
  Vec2 uniform2() {
    const double a = uniform();
    return {a, uniform()};
  }
};

// ---------------------------------------------------------------------------------------------
// Chi-square distribution
// ---------------------------------------------------------------------------------------------

/// Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a), a > 0, x >= 0
/// (series for x < a + 1, Lentz continued fraction otherwise; Numerical Recipes §6.2).
inline double gamma_q(double a, double x) {
  if (x <= 0) return 1.0;
  const double gln = std::lgamma(a);
  if (x < a + 1.0) {
    double ap = a, sum = 1.0 / a, del = sum;
    for (int n = 0; n < 100000; ++n) {
      ap += 1.0;
      del *= x / ap;
      sum += del;
      if (std::abs(del) < std::abs(sum) * 1e-15) break;
    }
    return 1.0 - sum * std::exp(-x + a * std::log(x) - gln);
  }
  const double fpmin = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / fpmin, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < fpmin) d = fpmin;
    c = b + an / c;
    if (std::abs(c) < fpmin) c = fpmin;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < 1e-15) break;
  }
  return std::exp(-x + a * std::log(x) - gln) * h;
}

/// P(X >= stat) for X ~ chi-square with `dof` degrees of freedom.
inline double chi2_survival(double stat, int dof) { return gamma_q(0.5 * dof, 0.5 * stat); }

/// Per-test significance so that `count` independent tests together reject a correct
/// implementation with probability `family_significance` (Šidák; Mitsuba's chi2.py does this).
inline double sidak(double family_significance, int count) {
  return 1.0 - std::pow(1.0 - family_significance, 1.0 / count);
}

/// Result of chi2_test: passed, statistic, degrees of freedom, p-value, and a readable summary.
struct Chi2Result {
  bool passed = false;
  double statistic = 0;
  int dof = 0;
  double p_value = 0;
  std::string message;
};

/// Pearson chi-square test of observed counts against expected counts (same total), pooling as
/// Mitsuba's chi2.py: cells are visited by increasing expected count; cells with expected < 5 are
/// pooled together, and a pool still below 5 is merged into the next larger cell. A cell with expected == 0 but
/// observed > 0 fails immediately (a sample where the density says none can be). Rejects when p < significance.
inline Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                            double significance, double min_expected = 5.0) {
  Chi2Result r;
  std::vector<size_t> order(observed.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  double pooled_obs = 0, pooled_exp = 0, chsq = 0;
  int dof = 0, pooled_cells = 0;
  std::ostringstream msg;
  for (size_t i : order) {
    const double o = observed[i], e = expected[i];
    if (e <= 0) {
      if (o > 0) {
        msg << "cell " << i << ": " << o << " samples where the expected count is 0";
        r.message = msg.str();
        r.passed = false;
        return r;
      }
      continue;
    }
    if (e < min_expected) {
      pooled_obs += o;
      pooled_exp += e;
      ++pooled_cells;
    } else if (pooled_exp > 0 && pooled_exp < min_expected) {
      const double po = pooled_obs + o, pe = pooled_exp + e;
      chsq += (po - pe) * (po - pe) / pe;
      pooled_obs = pooled_exp = 0;
      ++dof;
    } else {
      chsq += (o - e) * (o - e) / e;
      ++dof;
    }
  }
  if (pooled_exp > 0) {  // a remainder smaller than min_expected: one more cell
    chsq += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
    ++dof;
  }
  dof -= 1;
  r.statistic = chsq;
  r.dof = dof;
  if (dof <= 0) {
    // Everything in one cell: the test has no power, but the totals must agree (checked by caller).
    r.p_value = 1.0;
    r.passed = true;
    r.message = "only one cell after pooling";
    return r;
  }
  r.p_value = chi2_survival(chsq, dof);
  r.passed = r.p_value >= significance;
  msg << "chi2 = " << chsq << ", dof = " << dof << ", p = " << r.p_value << " (significance " << significance << ", "
      << pooled_cells << " cells pooled)";
  r.message = msg.str();
  return r;
}

// ---------------------------------------------------------------------------------------------
// Spherical quadrature and binning
// ---------------------------------------------------------------------------------------------

/// Calls visit(direction, weight) for a midpoint quadrature of the unit sphere in polar
/// coordinates (theta', phi') around the unit direction `center`, with theta' = pi s^3 and s, phi'
/// uniform on n_s x n_phi cells: the cells shrink toward `center` (cell size ~ 3 pi s^2 / n_s in
/// theta'), so a density peaked at `center` with width ~1e-2 rad is resolved by thousands of
/// points. sum(weight) = 4 pi to O(1/n^2); integral f ~= sum f(direction) weight.
/// With theta_max < pi only the cap theta' < theta_max is covered (e.g. pi/2: the hemisphere
/// around `center`, so that a jump of the integrand at its rim falls on a cell boundary).
inline void sphere_quadrature(const Vec3& center, int n_s, int n_phi,
                              const std::function<void(const Vec3&, double)>& visit, double theta_max = kPi) {
  const Frame frame(center);
  const double ds = 1.0 / n_s, dphi = 2.0 * kPi / n_phi;
  std::vector<double> cos_phi(static_cast<size_t>(n_phi)), sin_phi(static_cast<size_t>(n_phi));
  for (int j = 0; j < n_phi; ++j) {
    cos_phi[size_t(j)] = std::cos((j + 0.5) * dphi);
    sin_phi[size_t(j)] = std::sin((j + 0.5) * dphi);
  }
  for (int i = 0; i < n_s; ++i) {
    const double s = (i + 0.5) * ds;
    const double theta = theta_max * s * s * s;
    const double dtheta = 3.0 * theta_max * s * s * ds;
    const double st = std::sin(theta), ct = std::cos(theta);
    const double w = st * dtheta * dphi;
    for (int j = 0; j < n_phi; ++j) {
      const Vec3 local(st * cos_phi[size_t(j)], st * sin_phi[size_t(j)], ct);
      visit(frame.to_world(local), w);
    }
  }
}

/// Integral of f over the unit sphere (or the cap theta' < theta_max) with sphere_quadrature.
inline double integrate_sphere(const Vec3& center, int n_s, int n_phi, const std::function<double(const Vec3&)>& f,
                               double theta_max = kPi) {
  double sum = 0;
  sphere_quadrature(
      center, n_s, n_phi, [&](const Vec3& d, double w) { sum += f(d) * w; }, theta_max);
  return sum;
}

/// Equal-area bins of the sphere over (cos theta, phi) in the frame whose z axis is the pole:
/// n_cos bins of cos theta in [-1,1] times n_phi bins of phi in [0, 2 pi).
struct SphereBins {
  int n_cos = 0, n_phi = 0;
  int count() const { return n_cos * n_phi; }
  int index(const Vec3& d) const {
    const double c = std::clamp(d.z(), -1.0, 1.0);
    int ic = int((c + 1.0) * 0.5 * n_cos);
    ic = std::clamp(ic, 0, n_cos - 1);
    double phi = std::atan2(d.y(), d.x());
    if (phi < 0) phi += 2.0 * kPi;
    int ip = int(phi / (2.0 * kPi) * n_phi);
    ip = std::clamp(ip, 0, n_phi - 1);
    return ic * n_phi + ip;
  }
};

/// Expected counts of `n_samples` samples of density pdf (per unit solid angle) in each bin:
/// the quadrature points of sphere_quadrature(center, ...) scattered into their bins (a cell is
/// assigned whole to the bin of its midpoint; with cells much finer than bins this errs by well
/// under 1e-3 of a bin's content). Also returns the total integral of the pdf in *total.
/// theta_max: as for sphere_quadrature (a pdf that vanishes beyond the cap and jumps at its rim,
/// e.g. a hemisphere's, is integrated exactly up to the rim instead of by cells straddling it).
inline std::vector<double> expected_counts(const SphereBins& bins, const Vec3& center, int n_s, int n_phi,
                                           double n_samples, const std::function<double(const Vec3&)>& pdf,
                                           double* total = nullptr, double theta_max = kPi) {
  std::vector<double> e(size_t(bins.count()), 0.0);
  double sum = 0;
  sphere_quadrature(center, n_s, n_phi, [&](const Vec3& d, double w) {
    const double p = pdf(d) * w;
    e[size_t(bins.index(d))] += p;
    sum += p;
  }, theta_max);
  for (double& x : e) x *= n_samples;
  if (total) *total = sum;
  return e;
}

}  // namespace qsil::test
