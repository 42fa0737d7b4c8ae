#pragma once
/// @file warped_area_sampling.h
/// The parameters of `--boundary was` (warped-area sampling, docs/architecture.md §15; the
/// estimator itself: qsil/integrators/warp_field.h), apart from it so that configurations
/// (EstimatorConfig, the command line, comparisons) need not include the path tracer.

#include "qsil/error.h"

#include <string>

namespace qsil {

/// The parameters of warped-area sampling ([WAS] §5; Mitsuba 3's `reparam_*` names them alike).
struct WarpedAreaSampling {
  int rays = 8;         ///< auxiliary rays per warped direction (N); [QSS] Fig. 10 uses 8 and 32
  double kappa = 1e5;   ///< concentration of their vMF distribution around the direction
  double exponent = 3;  ///< gamma of the harmonic weights (D + B)^-gamma
  /// Estimate the warp field's limit for infinitely many auxiliary rays without bias: a random
  /// level L >= 0 with P(L = l) = (1 - r) r^l, r = 2^-1.5, and the antithetic difference of the
  /// ratio estimates from rays x 2^L rays and from each half, over P(L = l) (the single-term
  /// randomised multilevel estimator of Blanchet & Glynn 2015, "Unbiased Monte Carlo for
  /// optimization and functions of expectations via multi-level randomization", WSC). Expected
  /// rays per warp: 2.2 x `rays`, at most kWarpMaxRays. False: the fixed-N ratio estimate
  /// (biased, [WAS] §5).
  bool unbiased = false;
};

/// The level ratio r of WarpedAreaSampling::unbiased: P(L >= l) = r^l.
inline constexpr double kWarpLevelRatio = 0.35355339059327373;  // 2^-1.5
/// Most auxiliary rays one warp of WarpedAreaSampling::unbiased traces: its highest level l_max
/// is the largest with rays x 2^l_max <= this, and takes the probability P(L >= l_max), so the
/// estimate's mean is that of the ratio estimate from rays x 2^l_max rays (a bias below 10^-5
/// of the fixed-N bias of 8 rays).
inline constexpr int kWarpMaxRays = 1 << 20;

/// Throws qsil::Error unless rays is in [1, 1024], kappa in [1, 1e8] and exponent in (1, 16]
/// (gamma > 1: a weight's limit far from the direction is then 0).
inline void check_warped_area_sampling(const WarpedAreaSampling& was) {
  if (was.rays < 1 || was.rays > 1024)
    throw Error("was: auxiliary rays " + std::to_string(was.rays) + " out of range [1, 1024]");
  if (!(was.kappa >= 1 && was.kappa <= 1e8))
    throw Error("was: kappa " + std::to_string(was.kappa) + " out of range [1, 1e8]");
  if (!(was.exponent > 1 && was.exponent <= 16))
    throw Error("was: exponent " + std::to_string(was.exponent) + " out of range (1, 16]");
}

}  // namespace qsil
