#pragma once
/// @file quadric_sampler.h
/// The `quadric` and `quadric-box` edge samplers [QSS]: stochastic traversal of the edge forest
/// (sample_silhouette, silhouette_sampler.h) with the forest's rejection test, the dual box and
/// the bounding quadric pair (Method::Quadric) or the dual box only (Method::QuadricBox).

#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/edge_sampler.h"

namespace qsil::edgetree {

/// sample_silhouette over a forest with the rejection test of `method`.
class QuadricEdgeSampler final : public EdgeSampler {
 public:
  /// `method`: Method::Quadric or Method::QuadricBox. The forest must outlive the sampler; for
  /// Quadric its nodes must carry quadrics (NodeFitOptions::fit_quadrics), for QuadricBox they
  /// need not (the box test uses nothing of the quadric).
  QuadricEdgeSampler(const EdgeForest& forest, Method method);
  SilhouetteSample sample(const SilhouetteQuery& query, const std::function<double()>& next) const override;
  /// sample_silhouette_set: splits bright loose always-candidate edges off the traversal, and
  /// estimates the query's contour set (SilhouetteQuery::contour) by a strategy of its own.
  void sample_set(const SilhouetteQuery& query, const std::function<double()>& next,
                  SilhouetteSampleSet& out) const override;
  Method method() const override { return method_; }

 private:
  const EdgeForest& forest_;
  Method method_;
};

}  // namespace qsil::edgetree
