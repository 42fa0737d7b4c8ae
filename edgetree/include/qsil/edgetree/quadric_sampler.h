#pragma once
/// @file quadric_sampler.h
/// The `quadric` and `quadric-box` edge samplers [QSS]: stochastic traversal of the edge forest
/// (sample_silhouette, silhouette_sampler.h) with the forest's rejection test, the dual box and
/// the bounding quadric pair (NodeTest::DualBoxAndQuadrics) or the dual box only (NodeTest::DualBox).

#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/edge_sampler.h"
#include "qsil/edgetree/node_rejection.h"

namespace qsil::edgetree {

/// sample_silhouette over a forest with the rejection test `test`.
class QuadricEdgeSampler final : public EdgeSampler {
 public:
  /// The forest must outlive the sampler; for NodeTest::DualBoxAndQuadrics its nodes must carry
  /// quadrics (NodeFitOptions::fit_quadrics), for NodeTest::DualBox they need not (the box test uses nothing of the quadric).
  QuadricEdgeSampler(const EdgeForest& forest, NodeTest test);
  SilhouetteSample sample(const SilhouetteQuery& query, const std::function<double()>& next) const override;
  /// sample_silhouette_set: splits bright loose always-candidate edges off the traversal, and
  /// estimates the query's contour set (SilhouetteQuery::contour) by a strategy of its own.
  void sample_set(const SilhouetteQuery& query, const std::function<double()>& next,
                  SilhouetteSampleSet& out) const override;
  std::string_view name() const override {
    return test_ == NodeTest::DualBoxAndQuadrics ? "quadric" : "quadric-box";
  }

 private:
  const EdgeForest& forest_;
  NodeTest test_;
};

}  // namespace qsil::edgetree
