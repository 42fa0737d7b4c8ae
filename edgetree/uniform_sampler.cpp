/// @file uniform_sampler.cpp
/// See uniform_sampler.h.

#include "qsil/edgetree/uniform_sampler.h"

#include "edge_point_sampler.h"

#include <algorithm>

namespace qsil::edgetree {

double UniformEdgeSampler::weight(const Edge& e) {
  const bool always = e.f1 < 0 || e.cls == EdgeClass::Boundary || e.cls == EdgeClass::NonManifold ||
                      e.cls == EdgeClass::Inconsistent || e.cls == EdgeClass::Intersection;
  return e.length * (always ? kPi : e.angle);
}

UniformEdgeSampler::UniformEdgeSampler(const EdgeSet& edges) {
  auto add = [&](const Edge& e) {
    const double w = weight(e);
    if (!(w > 0)) return;  // a zero-length edge contributes nothing
    if (e.shape >= int(shapes_.size())) shapes_.resize(size_t(e.shape) + 1);
    ShapeTable& t = shapes_[size_t(e.shape)];
    t.edges.push_back(&e);
    t.total += w;
    t.cdf.push_back(t.total);
  };
  for (const Edge& e : edges.edges()) add(e);
  for (const Edge& e : edges.always_edges()) add(e);
}

SilhouetteSample UniformEdgeSampler::sample(const SilhouetteQuery& query, const std::function<double()>& next) const {
  SilhouetteSample s;
  double sum = 0;
  for (size_t k = 0; k < shapes_.size(); ++k)
    if (query.is_eligible(int(k))) sum += shapes_[k].total;
  if (!(sum > 0)) return s;
  // ---- The shape, then the edge within it (one uniform number, rescaled).
  double u = next() * sum;
  const ShapeTable* t = nullptr;
  for (size_t k = 0; k < shapes_.size(); ++k) {
    if (!query.is_eligible(int(k)) || !(shapes_[k].total > 0)) continue;
    t = &shapes_[k];
    if (u < shapes_[k].total) break;
    u -= shapes_[k].total;
  }
  u = std::min(u, t->total);
  size_t i = size_t(std::upper_bound(t->cdf.begin(), t->cdf.end(), u) - t->cdf.begin());
  i = std::min(i, t->edges.size() - 1);
  const Edge& e = *t->edges[i];
  return sample_on_edge(e, weight(e) / sum, query, next());  // no edge for a non-discontinuity: a zero sample
}

std::vector<EdgeProbability> UniformEdgeSampler::edge_probabilities(const SilhouetteQuery& query) const {
  std::vector<EdgeProbability> out;
  double sum = 0;
  for (size_t k = 0; k < shapes_.size(); ++k)
    if (query.is_eligible(int(k))) sum += shapes_[k].total;
  if (!(sum > 0)) return out;
  for (size_t k = 0; k < shapes_.size(); ++k) {
    if (!query.is_eligible(int(k))) continue;
    for (const Edge* e : shapes_[k].edges) out.push_back({e, weight(*e) / sum});
  }
  return out;
}

}  // namespace qsil::edgetree
