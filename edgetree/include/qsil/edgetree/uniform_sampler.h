#pragma once
/// @file uniform_sampler.h
/// The `uniform` edge sampler (docs/architecture.md §7): a floor for the comparisons. No hierarchy and no
/// rejection: among the edges of the eligible shapes (the edge set's tree edges and its
/// always-candidate edges) an edge is chosen with probability proportional to
///   w_e = length * exterior dihedral angle   (tree edges; redner's secondary_edge_weight idea)
///   w_e = length * pi                        (always-candidate, i.e. boundary, edges)
/// and the point on it by EdgePointSampler. A chosen edge that is not a silhouette for the
/// shading point is returned as "no edge" (a zero-contribution sample), which is what makes
/// this the floor: every silhouette edge keeps its probability w_e / sum of eligible w.
///
/// Per shape a cumulative table over its edges; a query draws the shape among the eligible ones
/// (a loop over shapes) and then the edge by binary search. No per-query allocation.

#include "qsil/edgetree/edge_sampler.h"
#include "qsil/edgetree/edge_set.h"

#include <functional>
#include <string>
#include <vector>

namespace qsil::edgetree {

class UniformEdgeSampler final : public EdgeSampler {
 public:
  /// Tables over the edge set's edges (the set must outlive the sampler).
  explicit UniformEdgeSampler(const EdgeSet& edges);

  SilhouetteSample sample(const SilhouetteQuery& query, const std::function<double()>& next) const override;
  std::string_view name() const override { return "uniform"; }

  /// Every edge of the eligible shapes with its probability (they sum to 1 unless no shape is
  /// eligible).
  std::vector<EdgeProbability> edge_probabilities(const SilhouetteQuery& query) const;

  /// The sampling weight w_e of an edge (see the file comment).
  static double weight(const Edge& e);

 private:
  struct ShapeTable {
    std::vector<const Edge*> edges;
    std::vector<double> cdf;  ///< inclusive prefix sums of the weights
    double total = 0;
  };
  std::vector<ShapeTable> shapes_;
};

}  // namespace qsil::edgetree
