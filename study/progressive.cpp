/// @file progressive.cpp
/// See qsil/study/progressive.h.

#include "qsil/study/progressive.h"

#include "qsil/error.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace qsil {

uint64_t derive_seed(uint64_t base, int index) {
  uint64_t z = base + 0x9E3779B97F4A7C15ull * (uint64_t(index) + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

ProgressiveResult render_progressive(const PassFunction& pass, const ProgressiveOptions& options) {
  const bool budgeted = options.budget_seconds > 0;
  if (!budgeted && options.max_passes <= 0) throw Error("progressive rendering needs a budget or a pass count");
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(clock::now() - start).count(); };

  ProgressiveResult out;
  long long total_spp = 0;
  int next_spp = options.fixed_pass_spp > 0 ? options.fixed_pass_spp : std::max(1, options.first_pass_spp);
  for (int i = 0;; ++i) {
    // ---- one pass over the next sample range; progress bars off (many short passes)
    RenderOptions ro;
    ro.spp = next_spp;
    ro.first_sample = int(total_spp);
    ro.seed = options.seed;
    ro.threads = options.threads;
    ro.progress = false;
    RenderResult r = pass(ro);
    if (i == 0)
      out.result = std::move(r);
    else
      out.result.merge(r);
    total_spp += next_spp;
    out.passes = i + 1;

    // ---- stop, or size the next pass from the measured cost per sample
    if (options.max_passes > 0 && out.passes >= options.max_passes) break;
    if (!budgeted) continue;
    const double t = elapsed();
    const double remaining = options.budget_seconds - t;
    if (remaining <= 0) break;
    if (options.fixed_pass_spp > 0) {
      const double per_pass = t / out.passes;
      if (per_pass > remaining) break;
      continue;
    }
    const double per_spp = t / double(total_spp);
    const double fits = std::floor(remaining / per_spp);
    if (fits < 1) break;
    next_spp = int(std::min<double>({fits, double(std::max<long long>(total_spp, 1)), 1 << 20}));
  }
  out.wall_seconds = elapsed();
  return out;
}

}  // namespace qsil
