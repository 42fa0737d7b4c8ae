#pragma once
/// @file boundary_schedule.h
/// How many secondary boundary traversals a path vertex makes: the per-pixel stratified rate
/// (boundary_traversals) and splitting at fast shading points (boundary_split).

#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/integrators/boundary_context.h"
#include "qsil/rng.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace qsil {

/// How many secondary boundary traversals sample `sample` of pixel `pixel` makes at each vertex of
/// its path, at `rate` = BoundaryContext::sppi: the whole part of the rate, plus one
/// where a stratified pick over the pixel's samples selects it: with f the fraction of the rate
/// and phi uniform in [0, 1) drawn once per pixel (stream::kBoundarySchedule: the same for every
/// sample range and process split), sample s is picked iff floor(f (s + 1) + phi) > floor(f s +
/// phi). Every sample is picked with probability f (phi is uniform, to its 32 bits), so weighting each
/// traversal by 1 / rate is unbiased; and any n consecutive samples hold floor(f n) or ceil(f n)
/// picks, so unlike Russian roulette per sample the term's own mean adds no variance (a rate of
/// 1/2 is one boundary estimate every other sample, the sppi of Mitsuba 3's projective
/// integrators). The pixel's samples are then not identically distributed, so the estimator marks
/// the picked ones as a stratum of their own (Film::add_sample), whose variance the film's
/// standard error takes apart.
inline int boundary_traversals(double rate, uint64_t seed, uint64_t pixel, uint64_t sample) {
  const int whole = int(rate);
  const double f = rate - double(whole);
  if (!(f > 0)) return whole;
  const double phi = Sampler(seed, pixel, 0, stream::kBoundarySchedule).next();
  const double s = double(sample);
  return whole + int(std::floor(f * (s + 1.0) + phi) - std::floor(f * s + phi));
}

/// The stream from which the secondary boundary term of sample `sample` of pixel `pixel` draws:
/// one of its own (stream::kBoundary), so that the boundary term leaves the path's decisions
/// unchanged, and a retrace of the sample (sample_trace.h) draws the same edge points.
inline Sampler boundary_stream(uint64_t seed, uint64_t pixel, uint64_t sample) {
  return Sampler(seed, pixel, sample, stream::kBoundary);
}

/// The most traversals boundary_split makes of one.
inline constexpr int kMaxBoundarySplit = 16;

/// How many traversals stand for each one boundary_traversals schedules at the vertex of query `q`
/// (splitting, as in adjoint-driven Russian roulette and splitting, Vorba & Křivánek 2016, with the
/// shading point's speed as the driver): with s = max_k |dp/dtheta_k| velocity_scale[k], the speed
/// of p in units of the fastest mesh vertex of each parameter (q.dp, q.velocity_scale; 0 without
/// q.velocities, e.g. reverse mode), ceil(s / boundary_ctx.split_speed) clamped to [1,
/// kMaxBoundarySplit]; 1 when boundary_ctx.split_speed is 0.
/// Why: with directions fixed, a point a ray meets on a moving surface at an angle of incidence
/// with cosine c slides along the ray at about 1/c the surface's speed, so J = n . (v - dp) of
/// every edge seen from p grows with s, and so does the variance of one traversal's estimate
/// (the choice of edge; the variance across pixel samples of the exact value is another matter).
/// Splitting a traversal into m, each weighted 1/m, keeps the estimate unbiased for any m that
/// depends only on the vertex (p, dp), and divides that variance by m at m times the cost; m
/// proportional to s is the allocation that minimises variance x cost when the variance grows
/// as s^2 (the rate's own argument, docs/design-notes.md "How many boundary samples per pixel
/// sample", per vertex). Such points are rare (grazing hits), so the cost stays small: measured
/// in docs/architecture.md §5 "Splitting at fast shading points".
inline int boundary_split(const BoundaryContext& boundary_ctx, const edgetree::SilhouetteQuery& q) {
  if (!(boundary_ctx.split_speed > 0) || !q.velocities) return 1;
  double speed = 0;
  for (int k = 0; k < q.velocities->num_params; ++k)
    speed = std::max(speed, q.dp.col(k).norm() * q.velocity_scale[size_t(k)]);
  // The clamp before the conversion keeps a non-finite speed from becoming an undefined int.
  return int(std::clamp(std::ceil(speed / boundary_ctx.split_speed), 1.0, double(kMaxBoundarySplit)));
}

}  // namespace qsil
