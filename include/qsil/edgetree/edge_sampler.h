#pragma once
/// @file edge_sampler.h
/// The interface of every secondary boundary-term edge sampler (`--boundary`, docs/architecture.md §7):
/// given a shading point, sample one discontinuity edge and a point on it, with the exact
/// probability density of having done so. Implementations: QuadricEdgeSampler (the edge forest
/// with the quadric or box-only rejection test, silhouette_sampler.h); the baselines of issue 6
/// (Li 2019's v-sphere tree, uniform) plug in here too.
///
/// Contract (unbiasedness, docs/architecture.md §5): for every edge that is a discontinuity for the query
/// point and eligible (SilhouetteQuery::eligible), the probability of returning it must be > 0,
/// and so must the density of every t on it; `pdf` is the product of the discrete probability
/// and the density of t. Returning no edge is allowed (a zero-contribution sample).

#include "qsil/edgetree/silhouette_sampler.h"

#include <functional>
#include <string>

namespace qsil::edgetree {

class EdgeSampler {
 public:
  virtual ~EdgeSampler() = default;
  /// One edge point for the query; `next` returns fresh uniform numbers in [0, 1).
  virtual SilhouetteSample sample(const SilhouetteQuery& query, const std::function<double()>& next) const = 0;
  /// The method's name as given to --boundary.
  virtual std::string name() const = 0;
};

/// The quadric edge forest [QSS]: sample_silhouette with the query's rejection mode forced to
/// `mode` (Quadric for `quadric`, Box for `quadric-box`).
class QuadricEdgeSampler final : public EdgeSampler {
 public:
  QuadricEdgeSampler(const EdgeForest& forest, RejectionMode mode) : forest_(forest), mode_(mode) {}
  SilhouetteSample sample(const SilhouetteQuery& query, const std::function<double()>& next) const override {
    SilhouetteQuery q = query;
    q.mode = mode_;
    return sample_silhouette(forest_, q, next);
  }
  std::string name() const override { return mode_ == RejectionMode::Quadric ? "quadric" : "quadric-box"; }

 private:
  const EdgeForest& forest_;
  RejectionMode mode_;
};

}  // namespace qsil::edgetree
