#pragma once
/// @file estimator_runs.h
/// What tests that run an Estimator and compare image sums share: quiet run options, the image
/// sum of the first derivative channel, and the message of an expected refusal.

#include "qsil/integrators/estimator.h"

#include "qsil/error.h"

#include <cstdint>
#include <functional>
#include <string>

namespace qsil::test {

/// Options of a run of `spp` samples per pixel with seed `seed`, without a progress bar.
inline RenderOptions quiet(int spp, uint64_t seed) {
  RenderOptions o;
  o.spp = spp;
  o.seed = seed;
  o.progress = false;
  return o;
}

/// An image sum and its standard error.
struct Sum {
  double value = 0, se = 0;
};

/// The image sum of parameter 0's derivative (Film::derivative_sum).
inline Sum derivative_sum(const RenderResult& r) {
  const ImageSum s = r.film.derivative_sum(0);
  return {s.sum, s.standard_error};
}

/// The message of the qsil::Error that `f` throws, or "(no error)".
inline std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) { return e.what(); }
  return "(no error)";
}

}  // namespace qsil::test
