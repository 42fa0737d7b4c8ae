#pragma once
/// @file discrete_choice.h
/// Drawing one of a few candidates with given probabilities, shared by every edge sampler.

namespace qsil::edgetree {

/// Index drawn with probabilities prob[0..n) (which sum to 1 up to rounding) from u in [0,1);
/// never an index of zero probability, even when rounding leaves u beyond the last sum (the
/// authors' code returned index 0 there: a possibly zero-probability choice, docs/architecture.md §5).
/// Returns -1 only when every probability is 0.
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
