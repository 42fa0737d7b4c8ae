/// @file sampling.cpp
/// Warps and piecewise-constant distributions (see include/qsil/sampling.h).

#include "qsil/sampling.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace qsil {

namespace {
/// Largest double below 1: the upper end of every "[0,1)" output.
constexpr double kOneMinusEpsilon = 1.0 - std::numeric_limits<double>::epsilon() / 2;
}  // namespace

// ---------------------------------------------------------------------------------------------
// Warps
// ---------------------------------------------------------------------------------------------

Vec3 square_to_uniform_sphere(const Vec2& u) {
  // z uniform in [-1,1] (Archimedes), phi uniform.
  const double z = 1.0 - 2.0 * u.x();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2.0 * kPi * u.y();
  return {r * std::cos(phi), r * std::sin(phi), z};
}

VonMisesFisherSample square_to_von_mises_fisher(const Vec2& u, double kappa) {
  // x in (exp(-2 kappa), 1]: 1 - cos = -log(x) / kappa; sin^2 = (1 - cos)(1 + cos).
  const double x = u.x() + (1.0 - u.x()) * std::exp(-2.0 * kappa);
  const double s = x > 0 ? std::clamp(-std::log(x) / kappa, 0.0, 2.0) : 2.0;
  const double r = std::sqrt(std::max(0.0, s * (2.0 - s)));
  const double phi = 2.0 * kPi * u.y();
  return {Vec3(r * std::cos(phi), r * std::sin(phi), 1.0 - s), s};
}

double von_mises_fisher_pdf(double one_minus_cos, double kappa) {
  return kappa * std::exp(-kappa * one_minus_cos) / (2.0 * kPi * -std::expm1(-2.0 * kappa));
}

Vec3 square_to_uniform_hemisphere(const Vec2& u) {
  const double z = u.x();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2.0 * kPi * u.y();
  return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec2 square_to_concentric_disk(const Vec2& u) {
  // pbrt-v4 SampleUniformDiskConcentric.
  const double ox = 2.0 * u.x() - 1.0, oy = 2.0 * u.y() - 1.0;
  if (ox == 0.0 && oy == 0.0) return Vec2::Zero();
  double r, theta;
  if (std::abs(ox) > std::abs(oy)) {
    r = ox;
    theta = 0.25 * kPi * (oy / ox);
  } else {
    r = oy;
    theta = 0.5 * kPi - 0.25 * kPi * (ox / oy);
  }
  return {r * std::cos(theta), r * std::sin(theta)};
}

Vec3 square_to_cosine_hemisphere(const Vec2& u) {
  const Vec2 d = square_to_concentric_disk(u);
  const double z = std::sqrt(std::max(0.0, 1.0 - d.squaredNorm()));
  return {d.x(), d.y(), z};
}

Vec3 square_to_uniform_triangle(const Vec2& u) {
  // pbrt-v4 SampleUniformTriangle (Heitz 2019, "A Low-Distortion Map Between Triangle and Square").
  double b0, b1;
  if (u.x() < u.y()) {
    b0 = u.x() / 2;
    b1 = u.y() - b0;
  } else {
    b1 = u.y() / 2;
    b0 = u.x() - b1;
  }
  return {b0, b1, 1.0 - b0 - b1};
}

// ---------------------------------------------------------------------------------------------
// Distribution1D
// ---------------------------------------------------------------------------------------------

Distribution1D::Distribution1D(std::span<const double> f) {
  if (f.empty()) throw std::invalid_argument("Distribution1D: no bins");
  bins_.resize(f.size() + 1);
  guide_.resize(f.size() + 1);
  sum_ = build_bins(f, bins_.data(), guide_.data());
  is_zero_ = !(sum_ > 0.0);
}

double Distribution1D::build_bins(std::span<const double> f, Bin* bins, int* guide) {
  for (size_t i = 0; i < f.size(); ++i)
    if (!(f[i] >= 0.0) || !std::isfinite(f[i]))
      throw std::invalid_argument("Distribution1D: weight " + std::to_string(i) + " is negative or not finite");
  const size_t n = f.size();
  bins[0] = Bin{};
  for (size_t i = 0; i < n; ++i) {
    bins[i].f = f[i];
    bins[i + 1] = Bin{bins[i].cdf + f[i], 0.0};
  }
  const double sum = bins[n].cdf;
  if (!(sum > 0.0)) {
    // Degenerate: keep a uniform CDF so that sample() still yields well-formed numbers.
    for (size_t i = 0; i <= n; ++i) bins[i].cdf = double(i) / double(n);
  } else {
    // Dividing the prefix sums by their total keeps them monotone and makes the CDF's last value
    // exactly 1; a zero-weight bin keeps exactly zero width.
    for (size_t i = 1; i < n; ++i) bins[i].cdf /= sum;
    bins[n].cdf = 1.0;
  }
  // Guide table (the indexed search of Chen & Asau 1974): guide[k] = the largest i with
  // cdf[i] <= k/n, so the bin of u in [k/n, (k+1)/n) lies in [guide[k], guide[k+1]].
  size_t i = 0;
  for (size_t k = 0; k <= n; ++k) {
    const double level = double(k) / double(n);
    while (i + 1 <= n && bins[i + 1].cdf <= level) ++i;
    guide[k] = int(i);
  }
  return sum;
}

std::vector<double> Distribution1D::cdf() const {
  std::vector<double> c(bins_.size());
  for (size_t i = 0; i < bins_.size(); ++i) c[i] = bins_[i].cdf;
  return c;
}

int Distribution1D::find_bin(const Bin* bins, const int* guide, int n, double sum, double u) {
  // Largest i with cdf[i] <= u, clamped to [0, n-1]: searched between the guide table's bounds
  // (one or two steps for most u), and over the whole CDF when rounding of u n put u outside them
  // (the answer is the same as a binary search over the whole CDF, so sampling is unchanged).
  const auto below = [](double value, const Bin& b) { return value < b.cdf; };
  int i = -1;
  const double un = u * double(n);
  if (un >= 0.0 && un < double(n)) {
    const size_t k = size_t(un);
    const Bin* lo = bins + guide[k];
    const Bin* hi = bins + std::min<ptrdiff_t>(ptrdiff_t(n) + 1, ptrdiff_t(guide[k + 1]) + 2);
    i = int(std::upper_bound(lo, hi, u, below) - bins) - 1;
    const bool found = i >= 0 && bins[i].cdf <= u && (i == n || u < bins[i + 1].cdf);
    if (!found) i = -1;
  }
  if (i < 0) i = int(std::upper_bound(bins, bins + n + 1, u, below) - bins) - 1;
  i = std::clamp(i, 0, n - 1);
  if (!(sum > 0.0) || bins[i].f > 0.0) return i;
  // Rounding put u on a zero-width bin (u at or beyond the top of the CDF, or on a plateau):
  // move to the nearest bin of non-zero weight, preferring the one below (the CDF plateau is
  // reached from below), never a zero-probability bin and never an arbitrary fallback index.
  for (int j = i - 1; j >= 0; --j)
    if (bins[j].f > 0.0) return j;
  for (int j = i + 1; j < n; ++j)
    if (bins[j].f > 0.0) return j;
  return i;  // unreachable for a non-degenerate distribution
}

Distribution1D::Sample Distribution1D::sample_bins(const Bin* bins, const int* guide, int n, double sum, double u) {
  Sample s;
  if (n == 0) return s;
  u = std::clamp(u, 0.0, kOneMinusEpsilon);
  const int i = find_bin(bins, guide, n, sum, u);
  const Bin& bin = bins[i];
  const double width = bins[i + 1].cdf - bin.cdf;
  double du = width > 0.0 ? (u - bin.cdf) / width : 0.5;
  du = std::clamp(du, 0.0, kOneMinusEpsilon);
  double x = (double(i) + du) / double(n);
  // Keep x inside bin i despite rounding of (i + du)/n, so that pdf(x) refers to the same bin.
  while (x > 0.0 && int(x * n) > i) x = std::nextafter(x, 0.0);
  while (int(x * n) < i) x = std::nextafter(x, 1.0);
  s.x = x;
  s.index = i;
  if (sum > 0.0) {
    s.pmf = bin.f / sum;
    s.pdf = bin.f / (sum / double(n));
  }
  return s;
}

Distribution1D::Sample Distribution1D::sample(double u) const {
  return sample_bins(bins_.data(), guide_.data(), size(), sum_, u);
}

Distribution1D::Sample Distribution1D::sample_discrete(double u) const {
  Sample s = sample(u);
  // Position of u inside the chosen bin, reusable as a fresh uniform number.
  s.x = std::clamp(s.x * size() - s.index, 0.0, kOneMinusEpsilon);
  return s;
}

double Distribution1D::pdf(double x) const {
  if (is_zero_ || !(x >= 0.0) || !(x < 1.0)) return 0.0;
  const int i = std::min(int(x * size()), size() - 1);
  return bins_[size_t(i)].f / integral();
}

// ---------------------------------------------------------------------------------------------
// Distribution2D
// ---------------------------------------------------------------------------------------------

Distribution2D::Distribution2D(std::span<const double> f, int nu, int nv) : nu_(nu), nv_(nv) {
  if (nu <= 0 || nv <= 0 || f.size() != size_t(nu) * size_t(nv))
    throw std::invalid_argument("Distribution2D: size mismatch");
  const size_t row = size_t(nu) + 1;
  bins_.resize(row * size_t(nv));
  guide_.resize(row * size_t(nv));
  row_sum_.resize(size_t(nv));
  std::vector<double> row_integrals(static_cast<size_t>(nv));
  for (size_t v = 0; v < size_t(nv); ++v) {
    row_sum_[v] = Distribution1D::build_bins(f.subspan(v * size_t(nu), size_t(nu)), &bins_[v * row], &guide_[v * row]);
    row_integrals[v] = row_sum_[v] / double(nu);  // Distribution1D::integral()
  }
  marginal_ = Distribution1D(row_integrals);
}

Distribution2D::Sample Distribution2D::sample(const Vec2& u) const {
  Sample s;
  if (nv_ == 0) return s;
  const Distribution1D::Sample row = marginal_.sample(u.y());
  // The marginal never picks a row of zero integral, so the conditional is non-degenerate.
  const size_t first = size_t(row.index) * (size_t(nu_) + 1);
  const Distribution1D::Sample col =
      Distribution1D::sample_bins(&bins_[first], &guide_[first], nu_, row_sum_[size_t(row.index)], u.x());
  s.p = Vec2(col.x, row.x);
  s.iu = col.index;
  s.iv = row.index;
  s.pdf = row.pdf * col.pdf;
  return s;
}

double Distribution2D::pdf(const Vec2& p) const {
  if (marginal_.is_zero() || !(p.x() >= 0.0 && p.x() < 1.0 && p.y() >= 0.0 && p.y() < 1.0)) return 0.0;
  const int iu = std::min(int(p.x() * nu_), nu_ - 1);
  const int iv = std::min(int(p.y() * nv_), nv_ - 1);
  return bins_[size_t(iv) * (size_t(nu_) + 1) + size_t(iu)].f / marginal_.integral();
}

}  // namespace qsil
