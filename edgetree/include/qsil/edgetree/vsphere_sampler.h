#pragma once
/// @file vsphere_sampler.h
/// The `vsphere` and `vsphere-solid` edge samplers (docs/architecture.md §7; [QSS] Sec. 2.3, App. F): Li's
/// (2019) stochastic traversal of the Hough-space edge tree (vsphere_tree.h), as in redner, plus
/// the defensive share of our own sampler so that the estimator is unbiased for any BSDF.
///
/// Choice at every level (top level included) among the candidates that pass the rejection test:
///   P(i) = (1 - eps) I_i / sum I + eps G_i / sum G,   eps = kNodeDefensiveShare (1 if sum I = 0)
///   I_i = L_w * fmax / max(H, 1e-3 * diag(B_p))   [QSS Sec. 2.3: Li's importance]
///   G_i = L_w / max(H, diag(B_p)/2)^2            (the defensive weight of silhouette_sampler.h)
/// with H the distance from p to the centre of the child's spatial box B_p and fmax the LTC's
/// bound of f_s cos over the directions of B_p "as redner does": the largest cosine in the LTC's
/// cosine domain over the (transformed) box outline, times norm / pi, WITHOUT the LTC Jacobian
/// ([QSS] Sec. 2.3 notes this mismatch and keeps it; so do we). When p lies inside the parent's
/// spatial box every accepted child gets I = 1 (redner's rule: no bound is meaningful there).
/// Top level: each eligible shape's 6D root and plain root (when accepted) and each eligible
/// always-candidate edge, the latter weighted like a one-edge leaf with L_w = length * pi.
/// Leaves hold one edge and are tested with the v-sphere test only (no exact per-edge test, as
/// in Li's method): a chosen edge that is not a silhouette for p is returned as "no edge"
/// (a zero-contribution sample; the pdf of every silhouette edge is unchanged). The point on the
/// edge comes from EdgePointSampler (defensive as well).
///
/// No per-query heap allocation: the top-level candidates live in a thread-local buffer.

#include "qsil/edgetree/edge_sampler.h"
#include "qsil/edgetree/vsphere_tree.h"

#include <functional>
#include <string>
#include <vector>

namespace qsil::edgetree {

/// Li's max f_s bound of the LTC over the directions of a box seen from p (see the file comment):
/// norm / pi times the largest z of the unit directions M_inv w over the box's outline (1 when
/// the LTC's z axis is inside the transformed outline or p is inside the box), 0 if the box lies
/// entirely below the LTC's horizon. `frame` is the shading frame (world -> local). Per sr.
double vsphere_max_bsdf(const Box3& box, const Vec3& p, const Frame& frame, const LTC& ltc);

/// The `vsphere` / `vsphere-solid` sampler over a VSphereTree built for `hough_origin`.
class VSphereEdgeSampler final : public EdgeSampler {
 public:
  /// Builds the tree from the edge set's tree edges and creases (the set must outlive the
  /// sampler). `test`: the hollow or the solid v-sphere test.
  VSphereEdgeSampler(const EdgeSet& edges, const Vec3& hough_origin, VSphereTest test);

  SilhouetteSample sample(const SilhouetteQuery& query, const std::function<double()>& next) const override;
  std::string_view name() const override { return test_ == VSphereTest::Hollow ? "vsphere" : "vsphere-solid"; }

  /// Exhaustive traversal (every accepted child down to the leaves): every edge with non-zero
  /// probability of being chosen, silhouette or not, with that probability. The probabilities
  /// sum to at most 1 (the rest is the mass of traversals that end with both children rejected).
  std::vector<EdgeProbability> edge_probabilities(const SilhouetteQuery& query) const;

  const VSphereTree& tree() const { return tree_; }

 private:
  /// A candidate of a choice: a node (>= 0) or an always-candidate edge, with its weights.
  struct Buffers;  ///< the traversal's scratch buffers (vsphere_sampler.cpp)
  struct Cand {
    int node = -1;
    const Edge* edge = nullptr;
    double importance = 0, defensive = 0;
  };
  int top_candidates(const SilhouetteQuery& q, std::vector<Cand>& out, int& tests) const;
  /// Accepted children of inner node n with their weights (returns their number, 0..2).
  int child_candidates(int n, const SilhouetteQuery& q, Cand* out, int& tests) const;

  const EdgeSet& edges_;
  VSphereTree tree_;
  VSphereTest test_;
};

}  // namespace qsil::edgetree
