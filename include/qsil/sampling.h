#pragma once
/// @file sampling.h
/// Sampling utilities: warps from the unit square to common domains (with their densities) and
/// piecewise-constant 1D/2D distributions (pbrt-v4 §A.5 "Sampling Functions",
/// "PiecewiseConstant1D/2D"; Mitsuba 3 `core/warp.h`).
///
/// Conventions: every warp takes uniform numbers u in [0,1)^k; directions are unit vectors in a
/// local frame whose z axis is the "up" direction of the warp (the shading normal for BSDFs);
/// every pdf of a direction is per unit solid angle (sr^-1).
///
/// Robustness (docs/architecture.md §5 "Pitfalls"): the distributions never return a bin of zero
/// probability, not even when floating-point rounding of the CDF places u at a bin edge or when
/// u rounds up to 1; an all-zero input is handled explicitly (see Distribution1D).

#include "qsil/math.h"

#include <span>
#include <vector>

namespace qsil {

// ---------------------------------------------------------------------------------------------
// Warps (pbrt-v4 §A.5; Shirley & Chiu 1997 for the concentric disk)
// ---------------------------------------------------------------------------------------------

/// Uniform direction on the unit sphere S^2. pdf = 1/(4 pi).
Vec3 square_to_uniform_sphere(const Vec2& u);
/// Density of square_to_uniform_sphere, sr^-1.
inline double uniform_sphere_pdf() { return 0.25 * kInvPi; }

/// Uniform direction on the upper hemisphere z >= 0. pdf = 1/(2 pi) on z >= 0.
Vec3 square_to_uniform_hemisphere(const Vec2& u);
/// Density of square_to_uniform_hemisphere at a direction with cosine `cos_theta` (= v.z), sr^-1.
inline double uniform_hemisphere_pdf(double cos_theta) { return cos_theta >= 0 ? 0.5 * kInvPi : 0.0; }

/// Concentric (Shirley-Chiu) map of the square onto the unit disk; area-preserving up to the
/// constant pi, so a uniform u gives a uniform point (pdf = 1/pi per unit area).
Vec2 square_to_concentric_disk(const Vec2& u);

/// Cosine-weighted direction on the upper hemisphere (Malley's method: concentric disk lifted to
/// the hemisphere). pdf = cos(theta)/pi. The returned z is > 0 except for measure-zero u.
Vec3 square_to_cosine_hemisphere(const Vec2& u);
/// Density of square_to_cosine_hemisphere at a direction with cosine `cos_theta`, sr^-1
/// (0 below the horizon).
inline double cosine_hemisphere_pdf(double cos_theta) { return cos_theta > 0 ? cos_theta * kInvPi : 0.0; }

/// A direction drawn from the von Mises-Fisher distribution around +z, with 1 - cos(theta) kept
/// exactly (the direction's z rounds it away at large kappa).
struct VonMisesFisherSample {
  Vec3 dir;                  ///< unit
  double one_minus_cos = 0;  ///< 1 - dir.z, in [0, 2]
};

/// The von Mises-Fisher distribution on S^2 around +z with concentration kappa > 0, density
/// kappa exp(kappa (cos theta - 1)) / (2 pi (1 - exp(-2 kappa))) per steradian; inversion of
/// cos theta = 1 + log(u.x + (1 - u.x) exp(-2 kappa)) / kappa, phi = 2 pi u.y (W. Jakob 2012,
/// "Numerically stable sampling of the von Mises-Fisher distribution on S^2"). Stable for
/// kappa up to 1e8 and beyond.
VonMisesFisherSample square_to_von_mises_fisher(const Vec2& u, double kappa);
/// Density of square_to_von_mises_fisher at a direction with 1 - cos theta = `one_minus_cos`, sr^-1.
double von_mises_fisher_pdf(double one_minus_cos, double kappa);

/// Uniform point on a triangle as barycentric coordinates (b0, b1, b2), b0+b1+b2 = 1
/// (pbrt-v4 SampleUniformTriangle, the area-preserving "square to triangle" map of Heitz 2019,
/// no rejection). A point is b0*p0 + b1*p1 + b2*p2; pdf = 1/area per unit area.
Vec3 square_to_uniform_triangle(const Vec2& u);

// ---------------------------------------------------------------------------------------------
// Piecewise-constant distributions
// ---------------------------------------------------------------------------------------------

/// A piecewise-constant density on [0,1) with n equal bins proportional to non-negative weights
/// f[0..n-1] (pbrt-v4 PiecewiseConstant1D on the unit domain).
///
/// - pdf(x) = f[i] / integral for x in bin i = floor(x n), where integral = sum(f)/n.
/// - pmf(i) = f[i] / sum(f).
/// - All-zero (or empty-sum) input: the distribution is *degenerate*: is_zero() is true,
///   integral() = 0, sample() returns pdf = 0 (an invalid sample the caller must discard; its
///   x and index are still valid numbers, uniform over [0,1)), and pdf()/pmf() return 0. This
///   makes "no light to sample" explicit instead of silently sampling uniformly.
/// - Never returns a bin with f[i] == 0 (for a non-degenerate distribution): the bin found by
///   binary search on the CDF is moved to the nearest non-zero bin when rounding put u on a
///   zero-width bin (u at a CDF plateau, or u rounding to the top of the CDF).
/// Throws std::invalid_argument on a negative or non-finite weight or an empty input.
class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(std::span<const double> f);
  explicit Distribution1D(const std::vector<double>& f) : Distribution1D(std::span<const double>(f)) {}

  /// A continuous sample: x in [0,1) (strictly inside bin `index`, x < 1), its density pdf on
  /// [0,1), and the bin index with its probability pmf. pdf = 0 marks an invalid sample (degenerate
  /// distribution).
  struct Sample {
    double x = 0;
    double pdf = 0;
    int index = 0;
    double pmf = 0;
  };
  /// Inverts the CDF at u in [0,1) (values outside are clamped), linearly inside the bin.
  Sample sample(double u) const;
  /// Discrete sample: the bin index chosen by sample(u) with its probability in .pmf (pmf = 0
  /// marks an invalid sample), and in .x the position of u inside the bin's CDF interval, a fresh
  /// uniform number in [0,1) (so one number can drive two decisions); .pdf is as for sample().
  Sample sample_discrete(double u) const;

  /// Density at x in [0,1) (x outside [0,1) gives 0).
  double pdf(double x) const;
  /// Probability of bin i.
  double pmf(int i) const { return is_zero_ ? 0.0 : bins_[size_t(i)].f / sum_; }
  /// Number of bins.
  int size() const { return bins_.empty() ? 0 : int(bins_.size()) - 1; }
  /// Integral of the (unnormalised) step function over [0,1): sum(f)/n.
  double integral() const { return sum_ / double(size()); }
  /// True when all weights are zero (nothing can be sampled).
  bool is_zero() const { return is_zero_; }
  /// Weight of bin i as given.
  double weight(int i) const { return bins_[size_t(i)].f; }
  /// The normalised CDF, n+1 values from 0 to exactly 1, as a new vector (two calls give two
  /// vectors: take iterators from one).
  std::vector<double> cdf() const;

 private:
  friend class Distribution2D;  // its rows are sampled by the same code (sample_bins)
  /// One bin's CDF and weight side by side, so that a sample reads one or two cache lines where
  /// two arrays took two or three (an environment map's rows do not stay in cache;
  /// tools/bench/bench_envmap.cpp).
  struct Bin {
    double cdf = 0;  ///< the normalised CDF at the bin's start (entry n: exactly 1)
    double f = 0;    ///< the bin's weight as given (entry n: 0)
  };
  /// Fills bins[0..n] and guide[0..n] for the weights f (n = f.size() >= 1) and returns their sum;
  /// throws as the constructor does. Distribution2D fills its rows, which live in one array, with it.
  static double build_bins(std::span<const double> f, Bin* bins, int* guide);
  /// The bin of u (find_bin) and sample() over n bins held elsewhere (a Distribution2D row).
  static int find_bin(const Bin* bins, const int* guide, int n, double sum, double u);
  static Sample sample_bins(const Bin* bins, const int* guide, int n, double sum, double u);
  std::vector<Bin> bins_;   ///< n + 1 entries
  std::vector<int> guide_;  ///< n + 1 entries: the largest i with cdf[i] <= k/n (find_bin)
  double sum_ = 0;
  bool is_zero_ = true;
};

/// A piecewise-constant density on [0,1)^2 over an nu x nv grid of non-negative weights
/// f[v * nu + u] (row v, column u; row 0 is at p.y() in [0, 1/nv)). Sampled as the marginal
/// over rows then the conditional over the chosen row's columns (pbrt-v4 PiecewiseConstant2D).
/// Never returns a cell of zero weight; an all-zero grid is degenerate (is_zero(), sample()
/// returns pdf = 0, pdf() returns 0). Throws std::invalid_argument on bad weights or sizes.
/// Each row is the Distribution1D of its weights (the same samples and densities, bit for bit);
/// the rows' bins and guide tables are held in one array each, not one pair per row, so that an
/// environment map's distribution is two large blocks (huge pages, tools/huge_page_new.cpp) rather
/// than thousands of small ones, each first touched page by page.
class Distribution2D {
 public:
  Distribution2D() = default;
  Distribution2D(std::span<const double> f, int nu, int nv);

  /// p in [0,1)^2 (x = column coordinate, y = row coordinate), density pdf on [0,1)^2, and the
  /// cell (iu, iv). pdf = 0 marks an invalid sample (degenerate distribution).
  struct Sample {
    Vec2 p = Vec2::Zero();
    double pdf = 0;
    int iu = 0;
    int iv = 0;
  };
  /// u in [0,1)^2: u.y() picks the row, u.x() the column.
  Sample sample(const Vec2& u) const;
  /// Density at p in [0,1)^2 (0 outside).
  double pdf(const Vec2& p) const;
  int nu() const { return nu_; }
  int nv() const { return nv_; }
  /// Integral of the unnormalised step function over [0,1)^2: sum(f)/(nu nv).
  double integral() const { return marginal_.integral(); }
  bool is_zero() const { return marginal_.is_zero(); }

 private:
  int nu_ = 0, nv_ = 0;
  /// The conditional distribution of row v: bins [v (nu + 1), (v + 1)(nu + 1)) of bins_ and
  /// guide_, and its weights' sum row_sum_[v] (Distribution1D's bins_, guide_ and sum_).
  std::vector<Distribution1D::Bin> bins_;
  std::vector<int> guide_;
  std::vector<double> row_sum_;
  Distribution1D marginal_;  ///< over rows, weights = row integrals
};

}  // namespace qsil
