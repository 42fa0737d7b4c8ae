#pragma once
/// @file bin_quadrature.h
/// Integrals of a function of t over kBins equal bins of [0, 1] by the composite midpoint rule
/// (kSub points per bin): the expected bin counts of chi-square tests on [0, 1] and their sum.
/// Shared by the edge point sampler and edge mixture tests.

#include <vector>

namespace qsil::test {

inline constexpr int kBins = 100;
inline constexpr int kSub = 2000;

/// Integral of f over each of kBins equal bins of [0, 1] (midpoint rule, kSub points per bin).
template <class F>
std::vector<double> bin_integrals(const F& f) {
  std::vector<double> out(kBins, 0.0);
  const double h = 1.0 / (double(kBins) * kSub);
  for (int b = 0; b < kBins; ++b) {
    double s = 0;
    for (int k = 0; k < kSub; ++k) s += f((b * kSub + k + 0.5) * h);
    out[size_t(b)] = s * h;
  }
  return out;
}

/// The sum of the values.
inline double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

}  // namespace qsil::test
