#pragma once
/// @file progressive.h
/// Progressive rendering for equal-time comparisons (`qsil compare`): an estimator is run in
/// sample passes, each pass with its own seed, and the passes' films are merged, until a
/// wall-clock budget is spent (or a fixed number of passes is done).
///
/// Pass sizes adapt to the measured cost: after each pass the cost per sample per pixel (wall
/// time of whole passes, so per-pass set-up such as the edge-forest build counts) predicts how
/// many samples still fit, and a pass is started only when at least one sample fits. Passes
/// grow geometrically (at most doubling the samples so far), so the prediction is refreshed
/// often while the per-pass overhead stays small. The first pass always runs.

#include "qsil/integrators/render.h"

#include <cstdint>
#include <functional>

namespace qsil {

/// One pass of an estimator: renders `options.spp` samples per pixel with `options.seed`.
using PassFunction = std::function<RenderResult(const RenderOptions& options)>;

/// How long and in what steps to render.
struct ProgressiveOptions {
  double budget_seconds = 1;  ///< wall-clock budget; <= 0 means no budget (use max_passes)
  int first_pass_spp = 1;     ///< samples per pixel of the first pass
  int fixed_pass_spp = 0;     ///< > 0: every pass has this many spp (no adaptation)
  int max_passes = 0;         ///< > 0: stop after this many passes
  uint64_t seed = 0;          ///< base seed; pass i uses progressive_pass_seed(seed, i)
  int threads = 0;            ///< worker threads of each pass (0 = all cores)
};

/// What progressive rendering produced.
struct ProgressiveResult {
  RenderResult result;   ///< merged film; spp = total samples per pixel; rays, nonfinite summed
  int passes = 0;
  double wall_seconds = 0;  ///< wall time of all passes including per-pass set-up
};

/// Seed of pass `pass` (0-based) derived from `base` by a SplitMix64 step, so that passes and
/// runs with nearby base seeds draw unrelated streams.
uint64_t progressive_pass_seed(uint64_t base, int pass);

/// Runs `pass` repeatedly (no progress bar) and merges the films in pass order.
/// Throws qsil::Error if neither a budget nor max_passes is given.
ProgressiveResult render_progressive(const PassFunction& pass, const ProgressiveOptions& options);

}  // namespace qsil
