#pragma once
/// @file rng.h
/// Deterministic random numbers: one PCG32 stream (O'Neill 2014, pcg-cpp from Debian) per
/// (seed, pixel, sample), so results are bit-identical for any thread count (docs/architecture.md §3).

#include "qsil/math.h"

#include <pcg_random.hpp>

#include <cstdint>

namespace qsil {

/// The dimension salts of Sampler: which independent use a stream serves. Named in one place so
/// that no two uses share a stream by accident (a shared stream correlates their decisions).
/// kBoundarySchedule and kWasAuxiliary share a value for history's sake (changing the first would
/// change every run with a fractional rate, the second every warped-area run): they never meet in
/// one run, as warped-area sampling has no edge sampler and so schedules no boundary traversals.
namespace stream {
/// A pixel sample's path (camera ray, BSDF and light samples).
inline constexpr uint64_t kPath = 0;
/// The secondary boundary term of a pixel sample's path (boundary_stream, boundary_schedule.h).
inline constexpr uint64_t kBoundary = 1;
/// Primary edge samples, per chunk (primary_boundary.h).
inline constexpr uint64_t kPrimary = 2;
/// The per-pixel phase of boundary_traversals (sample index 0).
inline constexpr uint64_t kBoundarySchedule = 3;
/// Warped-area sampling's auxiliary rays, per pixel sample.
inline constexpr uint64_t kWasAuxiliary = 3;
/// Warped-area sampling's pixel-border samples, per pixel sample.
inline constexpr uint64_t kWasBorder = 4;
/// Projective sampling's boundary segments, per chunk (projective_boundary.h).
inline constexpr uint64_t kProjectiveSegments = 5;
/// Projective sampling's grid guide: its uniform training segments, per chunk.
inline constexpr uint64_t kProjectiveTraining = 6;
/// Projective sampling's octree guide: its camera-path seeds, per chunk.
inline constexpr uint64_t kProjectiveSeeds = 7;
/// The attached camera hits' control-variate pre-pass, per pixel sample (attached_control.h).
inline constexpr uint64_t kAttachedControl = 8;
}  // namespace stream

/// Uniform sampler over one PCG32 stream.
class Sampler {
 public:
  /// The stream for sample `sample_index` of pixel `pixel_index` under user seed `seed`.
  /// `dimension_salt` (one of stream::) separates independent uses (e.g. FD's two sides share it
  /// on purpose).
  Sampler(uint64_t seed, uint64_t pixel_index, uint64_t sample_index, uint64_t dimension_salt = stream::kPath)
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
