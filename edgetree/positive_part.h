#pragma once
/// @file positive_part.h
/// The positive part of a quantity taken as uniform on a range: the cheap stand-in, shared by the
/// bounding-cone importances of boxes (silhouette_sampler.cpp) and the far-edge importance
/// (edge_mixture.cpp), for a cosine or a plane's side over a cone or along an edge, where X's
/// exact range is known but its distribution is not worth computing
/// (docs/architecture.md §5 "Importance").

#include <algorithm>

namespace qsil::edgetree {

/// E[max(0, X)] for X uniform on [lo, hi] (lo <= hi, any units; the result has X's units): (lo +
/// hi) / 2 when lo >= 0, 0 when hi <= 0, else hi² / 2 / (hi - lo) (the triangle up to the zero
/// crossing).
inline double mean_positive_part(double lo, double hi) {
  if (!(hi > 0)) return 0.0;
  if (lo >= 0) return 0.5 * (lo + hi);
  return 0.5 * hi * hi / (hi - lo);
}

/// P(X > 0) for X uniform on [lo, hi] (lo <= hi): 1 when lo >= 0, 0 when hi <= 0, else
/// hi / (hi - lo).
inline double positive_fraction(double lo, double hi) {
  if (lo >= 0) return 1.0;
  if (!(hi > 0)) return 0.0;
  return hi / (hi - lo);
}

}  // namespace qsil::edgetree
