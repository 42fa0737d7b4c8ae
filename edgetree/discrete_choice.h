#pragma once
/// @file discrete_choice.h
/// Choosing one of a few candidates, shared by every hierarchical edge sampler: the defensive
/// mixture of probabilities (docs/architecture.md §5 "Importance") and the draw itself.

#include "qsil/check.h"

#include <cmath>

namespace qsil::edgetree {

/// Defensive share eps of node and leaf-edge choices.
inline constexpr double kNodeDefensiveShare = 0.1;

/// The probabilities of a choice among n candidates with importances I_i and defensive weights
/// G_i (both >= 0, read by `importance(c[i])` and `defensive(c[i])`):
///   P(i) = (1 - eps) I_i / sum I + eps G_i / sum G,   eps = kNodeDefensiveShare (1 if sum I = 0),
/// and G uniform (1/n) when sum G = 0. They sum to 1 up to rounding (checked in debug builds).
template <class Candidates, class Importance, class Defensive>
void defensive_probabilities(const Candidates& c, int n, Importance&& importance, Defensive&& defensive, double* prob) {
  double si = 0, sg = 0;
  for (int i = 0; i < n; ++i) {
    si += importance(c[i]);
    sg += defensive(c[i]);
  }
  const double eps = si > 0 ? kNodeDefensiveShare : 1.0;
  double total = 0;
  for (int i = 0; i < n; ++i) {
    const double pi = si > 0 ? importance(c[i]) / si : 0.0;
    const double pg = sg > 0 ? defensive(c[i]) / sg : 1.0 / n;
    prob[i] = (1.0 - eps) * pi + eps * pg;
    total += prob[i];
  }
  QSIL_DCHECK_MSG(n == 0 || !(total > 1 + 1e-9), "probabilities sum to " << total);
}

/// Index drawn with probabilities prob[0..n) (which sum to at most 1 up to rounding) from u in
/// [0,1); never an index of zero probability, even when rounding leaves u beyond the last sum
/// (the authors' code returned index 0 there: a possibly zero-probability choice,
/// docs/architecture.md §5). Returns -1 only when every probability is 0.
inline int choose(const double* prob, int n, double u) {
  double acc = 0;
  int last = -1;
  for (int i = 0; i < n; ++i) {
    if (!(prob[i] > 0)) continue;
    acc += prob[i];
    last = i;
    if (u < acc) return i;
  }
  return last;
}

}  // namespace qsil::edgetree
