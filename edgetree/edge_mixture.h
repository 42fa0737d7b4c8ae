#pragma once
/// @file edge_mixture.h
/// The light-aware density of the point on a sampled edge, and the radiance-weighted edge
/// importance that comes with it (docs/architecture.md §5 "Importance" and "The point on the
/// edge"). Private to edgetree/.

#include "edge_point_sampler.h"
#include "qsil/edgetree/silhouette_sampler.h"

#include <array>
#include <span>
#include <vector>

namespace qsil::edgetree {

/// An edge relative to a query point p, in the world frame: what an edge's far-field importance
/// (EdgeMixture::far_total) and its normal-velocity factor (velocity_factor) share.
struct EdgeGeometry {
  Vec3 w0, w1;        ///< endpoints relative to p (scene units)
  Vec3 normal;        ///< w0 x w1: normal of the plane through p and the edge, |w0| |w1| sin(angle) long
  double normal_len;  ///< |w0 x w1|
  double mid2;        ///< |midpoint - p|^2
  EdgeGeometry(const Edge& e, const Vec3& p)
      : w0(e.p0 - p),
        w1(e.p1 - p),
        normal(w0.cross(w1)),
        normal_len(normal.norm()),
        mid2((0.5 * (w0 + w1)).squaredNorm()) {}
};

/// The per-query constants of an edge's importance (EdgeMixture::total): the map of world offsets
/// from p into the LTC's cosine domain (M_inv times the world-to-local rotation of q.frame), the
/// shading normal (world; w.z = normal . w) and norm |det M_inv| / pi. Built once per query, so
/// that an edge's importance maps each endpoint with one matrix product.
struct LtcMap {
  Mat3 to_cosine;
  Vec3 normal;
  double scale;
  explicit LtcMap(const SilhouetteQuery& q);
};

/// The density of t on edge e seen from the query point: the [QSS Eq. 4] × LTC target (f_s cos
/// over the edge, EdgePointSampler's LTC part) weighted by the radiance that can jump there,
///   p(t) = (1 − ε) Σ_i (W_i / W) p_i(t) + ε p_angle(t),   W_i = radiance_i × ∫ p_i's target,
/// with components: the environment's radiance (env_weight) plus, for the outline of an
/// emitter, its own (SilhouetteQuery::emission) over the whole edge; each quad light's radiance
/// over the part of the edge inside the light's pyramid from p (an interval of t: four linear
/// constraints), for the first kMaxLights lights whose emitting side faces p. ε =
/// kEdgeDefensiveShare (1 when W = 0) of angle-uniform samples over [0, 1] keeps p(t) > 0 on
/// the whole edge. W estimates the edge's radiance-weighted term: the edge's importance.
/// Construction costs one EdgePointSampler per component (a few dozen flops each).
class EdgeMixture {
 public:
  /// Lights beyond this many are not components (their part of the edge keeps the environment
  /// component and the defensive share).
  static constexpr int kMaxLights = 4;

  /// The mixture of edge e for the query; lights from q.lights (set up here).
  EdgeMixture(const Edge& e, const SilhouetteQuery& q);
  /// The same with the query's lights already set up (`lights` = local_lights(q)): what the
  /// traversal uses, once per query instead of once per edge.
  EdgeMixture(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights);

  /// W: the radiance-weighted LTC integral over the edge (luminance × per scene unit, ≥ 0).
  double total() const { return total_; }
  /// EdgeMixture(e, q, lights).total() without building the mixture (no component samplers, no
  /// angle-uniform part): an edge's importance, computed for every candidate of a leaf or a flat
  /// choice, of which one is sampled (EdgePointSampler::ltc_integral_mapped per component, in the
  /// world frame). Equal to total() up to rounding, and zero where it is zero up to rounding at
  /// the ends of an interval: an importance needs consistency between a choice and its
  /// probability, which the traversal and its probability walk get by calling this one function.
  static double total(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights);
  /// total(e, q, lights) with the per-query map and the edge's geometry relative to p already
  /// computed (leaf_edge_weight: once per query and once per edge).
  static double total(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights, const LtcMap& map,
                      const EdgeGeometry& g);
  /// total() for the cosine lobe (q.ltc's M_inv = I) with |w_t| taken as the distance d of the
  /// edge's midpoint from p: per component, radiance × |w0 × w1| / d⁴ × norm/π × ∫ max(0, w_t.z) dt
  /// over its interval of t (closed form, no angles). The traversal's importance for edges far
  /// from p (leaf_edge_weight); the relative error is O((half length / d)²). Zero exactly where
  /// total() is (the same components and horizon), up to rounding at the ends of an interval.
  static double far_total(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights);
  /// far_total from the edge's geometry relative to the query point, computed once for it and
  /// velocity_factor (leaf_edge_weight). Equal to far_total(e, q, lights) up to rounding.
  static double far_total(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights,
                          const EdgeGeometry& g);
  /// One sample from u in [0, 1): t in [0, 1] and its density pdf(t) > 0.
  EdgePointSample sample(double u) const;
  /// The density at t (per unit t): > 0 on [0, 1], 0 outside.
  double pdf(double t) const;

 private:
  std::array<EdgePointSampler, 1 + kMaxLights> comp_;
  std::array<double, 1 + kMaxLights> weight_{};
  int n_ = 0;
  double total_ = 0, eps_ = 1.0;
};

}  // namespace qsil::edgetree
