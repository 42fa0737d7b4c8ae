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

#include "qsil/edgetree/edge_forest.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/film.h"
#include "qsil/parameters.h"

namespace qsil {

/// One primary discontinuity edge: its visible parameter range and its projected segment.
struct PrimaryEdge {
  const edgetree::ForestEdge* edge = nullptr;
  double ta = 0, tb = 1;     ///< the part in front of the near plane and inside the frustum
  Vec2 a = Vec2::Zero(), b = Vec2::Zero();  ///< film positions (pixels) of ta and tb
  double za = 1, zb = 1;     ///< camera-space depths of ta and tb
  double length = 0;         ///< |b - a| in pixels
  /// Sampling weight (pixels): length for silhouettes and boundary edges, length * angle / pi
  /// for a crease, whose jump grows with its bend angle (always_edge_weight's scale): a smooth
  /// mesh's many shallow concave creases do not crowd out its silhouettes.
  double weight = 0;
};

/// The discontinuity edges of moving shapes seen from the camera centre, clipped and projected.
std::vector<PrimaryEdge> find_primary_edges(const Scene& scene, const edgetree::EdgeForest& forest,
                                            const std::vector<bool>& moving);

/// Film position (pixels, (0,0) top-left) of world point x, and its camera-space depth z (> 0 in
/// front). Inverse of Camera::direction.
Vec2 project_to_film(const Camera& camera, const Vec3& x, double* depth = nullptr);

/// Adds the primary boundary term to the derivative channels of `film` (layout of
/// gradient_film_channels(K)) with `num_samples` edge samples (0: none), deterministic for a seed
/// whatever the thread count. Counts rays and zero contributions in `stats`.
void add_primary_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                          const std::vector<PrimaryEdge>& edges, long long num_samples, int spp, uint64_t seed,
                          int threads, PathStats& stats);

}  // namespace qsil
