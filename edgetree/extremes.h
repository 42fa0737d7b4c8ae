#pragma once
/// @file extremes.h
/// The indices of the first smallest and the first largest of n values (extremal points along a
/// direction, for the enclosing sphere and the offset LP's working set).

#include "qsil/math.h"

#include <utility>

namespace qsil::edgetree {

/// Indices (imin, imax) of the first smallest and the first largest value(i) over i in [0, n).
/// The comparisons are strict and start from +inf / -inf, so a NaN value is never chosen (both
/// are 0 when every value is NaN or n = 0).
template <class Index, class Value>
std::pair<Index, Index> extreme_indices(Index n, Value&& value) {
  Index imin = 0, imax = 0;
  double vmin = kInf, vmax = -kInf;
  for (Index i = 0; i < n; ++i) {
    const double v = value(i);
    if (v < vmin) {
      vmin = v;
      imin = i;
    }
    if (v > vmax) {
      vmax = v;
      imax = i;
    }
  }
  return {imin, imax};
}

}  // namespace qsil::edgetree
