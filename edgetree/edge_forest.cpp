/// @file edge_forest.cpp
/// Parallel fitting of the edge set's inner nodes [QSS 4.2-4.4]; see qsil/edgetree/edge_forest.h.

#include "qsil/edgetree/edge_forest.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

namespace qsil::edgetree {

namespace {

// Fits one inner node from its edge range; `face_planes` are the shape's face planes.
NodeFit fit_range(const std::vector<Edge>& edges, const std::vector<Vec4>& face_planes, const ForestNode& n,
                  const NodeFit* parent, const NodeFitOptions& opt) {
  // Unique face planes of the patch (faces identified by index within the shape).
  std::vector<int> faces;
  faces.reserve(size_t(2) * (n.edge_end - n.edge_begin));
  std::vector<Wedge> wedges;
  wedges.reserve(size_t(n.edge_end - n.edge_begin));
  for (int i = n.edge_begin; i < n.edge_end; ++i) {
    const Edge& e = edges[size_t(i)];
    faces.push_back(e.f0);
    faces.push_back(e.f1);
    wedges.push_back({e.q0, e.q1});
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  std::vector<Vec4> planes;
  planes.reserve(faces.size());
  for (int fi : faces) planes.push_back(face_planes[size_t(fi)]);
  return fit_node(planes, wedges, n.bp, parent, opt);
}

}  // namespace

EdgeForest EdgeForest::build(std::span<const ForestShapeInput> shapes, const ForestOptions& options) {
  return fit(EdgeSet::build(shapes, options), options.fit);
}

EdgeForest EdgeForest::fit(EdgeSet set, const NodeFitOptions& options) {
  EdgeForest f;
  static_cast<EdgeSet&>(f) = std::move(set);
  for (size_t s = 0; s < f.trees_.size(); ++s) {
    const auto t0 = std::chrono::steady_clock::now();
    const ShapeTree& tree = f.trees_[s];
    ForestShapeStats& st = f.stats_[s];
    // ---- a bound slot per inner node, in node order
    const int bbase = int(f.bounds_.size());
    for (auto [lb, le] : tree.levels)
      for (int i = lb; i < le; ++i)
        if (!f.nodes_[size_t(i)].is_leaf()) {
          f.nodes_[size_t(i)].bound = int(f.bounds_.size());
          f.bounds_.emplace_back();
        }
    // ---- fit inner nodes level by level (parents first, for inheritance)
    std::vector<NodeFit> fits(f.bounds_.size() - size_t(bbase));
    for (auto [lb, le] : tree.levels) {
      tbb::parallel_for(lb, le, [&](int i) {
        ForestNode& n = f.nodes_[size_t(i)];
        if (n.is_leaf()) return;
        const NodeFit* parent = n.parent >= 0 ? &fits[size_t(f.nodes_[size_t(n.parent)].bound - bbase)] : nullptr;
        NodeFit fit = fit_range(f.edges_, tree.face_planes, n, parent, options);
        n.flags |= fit.flags;
        f.bounds_[size_t(n.bound)] = fit.bound;
        fits[size_t(n.bound - bbase)] = std::move(fit);
      });
    }
    // ---- statistics
    for (auto [lb, le] : tree.levels)
      for (int i = lb; i < le; ++i) {
        const ForestNode& n = f.nodes_[size_t(i)];
        if (n.is_leaf()) continue;
        st.fitted++;
        if (n.flags & kNodeUnrejectable)
          st.unrejectable++;
        else if (n.flags & kNodeBoxOnly)
          st.box_only++;
        else
          st.quadrics++;
        if (n.flags & kNodeInherited) st.inherited++;
        if (n.flags & kNodeUsedLp) st.used_lp++;
      }
    st.build_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  // What only fitting needed.
  f.trees_.clear();
  f.trees_.shrink_to_fit();
  return f;
}

size_t EdgeForest::memory_bytes() const { return EdgeSet::memory_bytes() + bounds_.capacity() * sizeof(NodeBound); }

}  // namespace qsil::edgetree
