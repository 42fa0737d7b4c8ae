#pragma once
/// @file primary_boundary.h
/// The primary boundary term: pixel coverage changes where silhouettes and outlines of moving
/// shapes cross the image (docs/architecture.md §6). The camera centre o is one fixed point, so its
/// discontinuity edges are found once per render: forest edges of moving shapes that are
/// silhouettes from o (exact per-edge test) and their always-candidate (boundary) edges, each
/// clipped against the near plane and the four frustum planes and projected to the image.
///
/// A pixel's value is (1/A) integral over the pixel of L dx (box filter, x in pixels, A = 1).
/// In solid angle, dx = W(w) dw with W(w) = f_x f_y / cos^3(theta) (pinhole; f the focal lengths
/// in pixels, theta the angle to the optical axis), so the boundary term of [QSS Eq. 3] applies
/// with W in place of the cosine-weighted BSDF:
///   dI_pixel/dtheta = sum_e integral s (L_bg - L_fg) W(w(t)) det(w0, w1, v_t)/|w_t|^3 dt
/// restricted to the t whose image point lies in the pixel. An edge is chosen with probability
/// proportional to PrimaryEdge::weight (projected length, times angle/pi for a crease) and a
/// point uniformly along its projected segment (so
/// the density in t carries the perspective Jacobian ds/dt); each sample is splatted into the
/// pixel it lands in.

#include "qsil/edgetree/edge_set.h"
#include "qsil/film.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/parameters.h"

#include <functional>

namespace qsil {

/// One primary discontinuity edge: its visible parameter range and its projected segment.
struct PrimaryEdge {
  const edgetree::ForestEdge* edge = nullptr;
  double ta = 0, tb = 1;                    ///< the part in front of the near plane and inside the frustum
  Vec2 a = Vec2::Zero(), b = Vec2::Zero();  ///< film positions (pixels) of ta and tb
  double za = 1, zb = 1;                    ///< camera-space depths of ta and tb
  double length = 0;                        ///< |b - a| in pixels
  /// Sampling weight (pixels): length for silhouettes and boundary edges, length * angle / pi
  /// for a crease, whose jump grows with its bend angle (always_edge_weight's scale): a smooth
  /// mesh's many shallow concave creases do not crowd out its silhouettes.
  double weight = 0;
};

/// The discontinuity edges of moving shapes seen from the camera centre, clipped and projected
/// (the edge set's tree and always-candidate edges; the edges point into `edges`).
std::vector<PrimaryEdge> find_primary_edges(const Scene& scene, const edgetree::EdgeSet& edges,
                                            const std::vector<bool>& moving);

/// Adds the primary boundary term of the sample range [first_sample, first_sample + spp) to the
/// derivative channels of `film` (a gradient film of velocities.num_params parameters): W x H
/// edge samples per sample index. The samples are numbered globally (sample index s owns numbers
/// [s W H, (s + 1) W H)) and drawn in chunks of 1024 numbers, chunk c from the stream
/// Sampler(seed, c, 0, 2) whichever run draws it, except that a chunk cut by the start of the
/// range draws its part from Sampler(seed, c, first_sample, 2). So a run over [0, spp) draws what
/// a single run of spp samples always drew; runs over disjoint ranges draw independent samples;
/// and when W H is a multiple of 1024 (every power-of-two image of 32 x 32 or more), runs over
/// ranges that partition [0, spp) draw exactly the samples of the run over [0, spp) (their films
/// merge into its film up to the rounding of the sums). Deterministic for a seed whatever the
/// thread count (chunks are merged in order). Counts rays and zero contributions in `stats`.
/// Part `part` of `parts` (RenderOptions::parts) draws only the part-th of `parts` contiguous
/// shares of the range's chunks (each exactly as the whole run draws it); with `deferred` its
/// splats are appended there in the order the whole run adds them, instead of to `film`.
void add_primary_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                          const std::vector<PrimaryEdge>& edges, int first_sample, int spp, uint64_t seed, int threads,
                          PathStats& stats, int part = 0, int parts = 1, std::vector<FilmSplat>* deferred = nullptr);

/// One contributing primary edge sample (reverse mode): the pixel it lands in, the edge point
/// (edge, t), its weight s (L_bg - L_fg) W / pdf per sample index, and g = (w0 x w1) / |w_t|^3:
/// the pixel's derivative gains weight (g . v) for an edge-point velocity v.
struct PrimarySample {
  int px = 0, py = 0;
  const edgetree::ForestEdge* edge = nullptr;
  double t = 0;
  Color weight = Color::Zero();
  Vec3 g = Vec3::Zero();
};
using PrimarySampleFn = std::function<void(const PrimarySample&)>;

/// The primary boundary term's samples of the range [first_sample, first_sample + spp), drawn
/// exactly as add_primary_boundary draws them (same streams, same chunks), but without velocities:
/// every sample whose edge point is visible and whose jump is non-zero is passed to `fn`, on the
/// calling thread, in chunk order (deterministic for a seed whatever the thread count). The edges
/// are those of the shapes whose vertices are differentiated. Counts rays and zero contributions.
void for_each_primary_sample(const PathContext& ctx, const std::vector<PrimaryEdge>& edges, int first_sample, int spp,
                             uint64_t seed, int threads, PathStats& stats, const PrimarySampleFn& fn);

}  // namespace qsil
