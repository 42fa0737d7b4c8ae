/// @file quadric_sampler.cpp
/// See qsil/edgetree/quadric_sampler.h.

#include "qsil/edgetree/quadric_sampler.h"

#include "qsil/check.h"

namespace qsil::edgetree {

QuadricEdgeSampler::QuadricEdgeSampler(const EdgeForest& forest, NodeTest test) : forest_(forest), test_(test) {
}

SilhouetteSample QuadricEdgeSampler::sample(const SilhouetteQuery& query, const std::function<double()>& next) const {
  return sample_silhouette(forest_, query, next, test_);
}

void QuadricEdgeSampler::sample_set(const SilhouetteQuery& query, const std::function<double()>& next,
                                    SilhouetteSampleSet& out) const {
  sample_silhouette_set(forest_, query, next, test_, out);
}

}  // namespace qsil::edgetree
