#pragma once
/// @file progressive.h
/// Progressive rendering for equal-time comparisons (`qsil compare`): an estimator is run in
/// passes over consecutive sample ranges ([0, n0), [n0, n0 + n1), ...; Estimator::run) and the
/// passes' films are merged, until a wall-clock budget is spent (or a fixed number of passes is
/// done). The estimator is set up once, before the first pass: its set-up is not part of any
/// pass (Estimator::setup() reports it). Because the passes cover disjoint sample ranges of one
/// seed, the merged film is the film of one run over all their samples, up to the rounding of
/// the merge.
///
/// Pass sizes adapt to the measured cost: after each pass the cost per sample per pixel (wall
/// time of whole passes) predicts how many samples still fit, and a pass is started only when at
/// least one sample fits. Passes grow geometrically (at most doubling the samples so far), so
/// the prediction is refreshed often while the per-pass overhead stays small. The first pass
/// always runs.

#include "qsil/integrators/estimator.h"

#include <cstdint>
#include <functional>

namespace qsil {

/// One pass: renders samples [options.first_sample, options.first_sample + options.spp) with
/// options.seed (usually `[&](const RenderOptions& o) { return estimator.run(o); }`).
using PassFunction = std::function<RenderResult(const RenderOptions& options)>;

/// How long and in what steps to render.
struct ProgressiveOptions {
  double budget_seconds = 1;  ///< wall-clock budget; <= 0 means no budget (use max_passes)
  int first_pass_spp = 1;     ///< samples per pixel of the first pass
  int fixed_pass_spp = 0;     ///< > 0: every pass has this many spp (no adaptation)
  int max_passes = 0;         ///< > 0: stop after this many passes
  uint64_t seed = 0;          ///< the seed of every pass (passes differ by their sample ranges)
  int threads = 0;            ///< worker threads of each pass (0 = all cores)
};

/// What progressive rendering produced.
struct ProgressiveResult {
  RenderResult result;  ///< merged film over samples [0, result.spp); rays, nonfinite etc. summed
  int passes = 0;
  double wall_seconds = 0;  ///< wall time of all passes
};

/// A seed derived from `base` and an index by a SplitMix64 step, so that runs with nearby base
/// seeds or indices draw unrelated streams (`qsil compare` gives every method and budget its own).
uint64_t derive_seed(uint64_t base, int index);

/// Runs `pass` over consecutive sample ranges starting at 0 (no progress bar) and merges the
/// films in pass order. Throws qsil::Error if neither a budget nor max_passes is given.
ProgressiveResult render_progressive(const PassFunction& pass, const ProgressiveOptions& options);

}  // namespace qsil
