#pragma once
/// @file rng.h
/// Deterministic random numbers: one PCG32 stream (O'Neill 2014, pcg-cpp from Debian) per
/// (seed, pixel, sample), so results are bit-identical for any thread count (docs/architecture.md §3).

#include "qsil/math.h"

#include <pcg_random.hpp>

#include <cstdint>

namespace qsil {

/// Uniform sampler over one PCG32 stream.
class Sampler {
 public:
  /// The stream for sample `sample_index` of pixel `pixel_index` under user seed `seed`.
  /// `dimension_salt` separates independent uses (e.g. FD's two sides share it on purpose).
  Sampler(uint64_t seed, uint64_t pixel_index, uint64_t sample_index, uint64_t dimension_salt = 0)
      : rng_(mix(seed ^ mix(sample_index + 0x9E3779B97F4A7C15ull * (dimension_salt + 1))), pixel_index) {}

  /// Uniform double in [0, 1) with 32 random bits (never 1).
  double next() { return double(rng_()) * 0x1p-32; }
  Vec2 next2() {
    const double a = next();
    return Vec2(a, next());
  }

 private:
  /// SplitMix64 finaliser: decorrelates nearby seeds.
  static uint64_t mix(uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  pcg32 rng_;
};

}  // namespace qsil
