#pragma once
/// @file edge_sampler.h
/// The interface of every secondary boundary-term edge sampler (`--boundary`, docs/architecture.md
/// §7): given a shading point, sample one discontinuity edge and a point on it, with the exact
/// probability density of having done so. Implementations: QuadricEdgeSampler (the edge forest
/// with the quadric or box-only rejection test, quadric_sampler.h), VSphereEdgeSampler (Li
/// 2019's Hough-space tree, vsphere_sampler.h) and UniformEdgeSampler (uniform_sampler.h).
///
/// Contract (unbiasedness, docs/architecture.md §5): for every edge that is a discontinuity for
/// the query point and eligible (SilhouetteQuery::eligible), the probability of returning it must
/// be > 0, and so must the density of every t on it; `pdf` is the product of the discrete
/// probability and the density of t. Returning no edge is allowed (a zero-contribution sample).
/// sample_set() may return several points (splitting); the same contract holds for each edge
/// under the strategy that covers it.

#include "qsil/edgetree/silhouette_sampler.h"
#include <functional>
#include <string_view>

namespace qsil::edgetree {

/// An edge and its probability of being chosen (the discrete part of a sampler's pdf), for
/// exhaustive enumerations (`qsil candidates`, the pdf tests).
struct EdgeProbability {
  const Edge* edge = nullptr;
  double probability = 0;
};

/// A secondary edge sampler (see the file comment).
class EdgeSampler {
 public:
  virtual ~EdgeSampler() = default;
  /// One edge point for the query; `next` returns fresh uniform numbers in [0, 1).
  virtual SilhouetteSample sample(const SilhouetteQuery& query, const std::function<double()>& next) const = 0;
  /// The edge points the renderer evaluates for the query: the boundary term there is estimated by
  /// the sum over `out` of integrand / pdf (each eligible discontinuity edge covered by exactly one
  /// of the set's strategies, with positive probability). Default: sample() alone (an empty set
  /// when it finds no edge); the edge forest splits bright loose edges off
  /// (sample_silhouette_set).
  virtual void sample_set(const SilhouetteQuery& query, const std::function<double()>& next,
                          SilhouetteSampleSet& out) const {
    out.count = 0;
    const SilhouetteSample s = sample(query, next);
    if (s.edge) out.push(s);
  }
  /// The name of the `--boundary` method it implements (e.g. "quadric").
  virtual std::string_view name() const = 0;
};

}  // namespace qsil::edgetree
