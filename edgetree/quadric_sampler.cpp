/// @file quadric_sampler.cpp
/// See qsil/edgetree/quadric_sampler.h.

#include "qsil/edgetree/quadric_sampler.h"

#include "qsil/check.h"

namespace qsil::edgetree {

QuadricEdgeSampler::QuadricEdgeSampler(const EdgeForest& forest, Method method, const ContourIndex* contours)
    : forest_(forest), method_(method), contours_(contours) {
  QSIL_CHECK(uses_edge_forest(method));
}

SilhouetteSample QuadricEdgeSampler::sample(const SilhouetteQuery& query, const std::function<double()>& next) const {
  return sample_silhouette(forest_, query, next, method_);
}

void QuadricEdgeSampler::sample_set(const SilhouetteQuery& query, const std::function<double()>& next,
                                    SilhouetteSampleSet& out) const {
  thread_local std::vector<const ForestEdge*> contour;
  contour.clear();
  if (contours_ && query.probe.count > 0) contours_->contour_edges(query.probe, query.p, query.eligible, contour);
  sample_silhouette_set(forest_, query, next, method_, out, contour);
}

}  // namespace qsil::edgetree
