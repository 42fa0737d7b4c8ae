/// @file edge_forest.cpp
/// Parallel fitting of the edge set's inner nodes [QSS 4.2-4.4]; see qsil/edgetree/edge_forest.h.

#include "qsil/edgetree/edge_forest.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

namespace qsil::edgetree {

namespace {

/// fit_range's arrays, one set per thread of a fit, reused from node to node (a level's nodes
/// together hold every edge: fresh arrays would be allocated, first touched and freed at every
/// level).
struct FitScratch {
  std::vector<std::pair<int, const Vec4*>> faces;  // (face, its plane), each face once
  std::vector<Wedge> wedges;
  std::vector<Vec4> planes;
  std::vector<int> stamp;  // per face + 1: the last node (`node`) that listed it
  int node = 0;
};

// Fits one inner node from its edge range: its wedges, and its unique face planes in face order
// (faces identified by index within the shape; each edge carries its faces' planes).
NodeFit fit_range(const std::vector<Edge>& edges, const ForestNode& n, const NodeFit* parent, const NodeFitOptions& opt,
                  FitScratch& scratch) {
  auto& [faces, wedges, planes, stamp, node] = scratch;
  faces.clear();
  wedges.clear();
  planes.clear();
  ++node;
  // A face is listed once, by its first edge (every edge of a face carries the same plane); the
  // faces are then sorted, a third as many as the edges' two sides.
  auto list = [&](int face, const Vec4& plane) {
    const size_t k = size_t(face + 1);  // a missing face is -1
    if (k >= stamp.size()) stamp.resize(std::max(k + 1, 2 * stamp.size()), 0);
    if (stamp[k] == node) return;
    stamp[k] = node;
    faces.push_back({face, &plane});
  };
  for (int i = n.edge_begin; i < n.edge_end; ++i) {
    const Edge& e = edges[size_t(i)];
    list(e.f0, e.q0);
    list(e.f1, e.q1);
    wedges.push_back({e.q0, e.q1});
  }
  std::sort(faces.begin(), faces.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& f : faces) planes.push_back(*f.second);
  return fit_node(planes, wedges, n.bp, parent, opt);
}

/// The size of a dual box: the sum of its extents (0 for a bound without one).
float box_size(const NodeBound& b) { return float((b.bq_hi - b.bq_lo).sum()); }

}  // namespace

EdgeForest EdgeForest::build(std::span<const ForestShapeInput> shapes, const ForestOptions& options) {
  return fit(EdgeSet::build(shapes, options), options.fit);
}

EdgeForest EdgeForest::fit(EdgeSet set, const NodeFitOptions& options) {
  EdgeForest f;
  static_cast<EdgeSet&>(f) = std::move(set);
  size_t inner = 0;  // every tree's inner nodes: the bounds' array is sized once
  for (const ShapeTree& tree : f.trees_)
    for (auto [lb, le] : tree.levels)
      for (int i = lb; i < le; ++i) inner += f.nodes_[size_t(i)].is_leaf() ? 0 : 1;
  f.bounds_.reserve(f.bounds_.size() + inner);
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
    tbb::enumerable_thread_specific<FitScratch> scratch;
    for (auto [lb, le] : tree.levels) {
      tbb::parallel_for(lb, le, [&](int i) {
        ForestNode& n = f.nodes_[size_t(i)];
        if (n.is_leaf()) return;
        const NodeFit* parent = n.parent >= 0 ? &fits[size_t(f.nodes_[size_t(n.parent)].bound - bbase)] : nullptr;
        NodeFit fit = fit_range(f.edges_, n, parent, options, scratch.local());
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
  f.fit_options_ = {options};
  f.fitted_box_size_.resize(f.bounds_.size());
  for (size_t b = 0; b < f.bounds_.size(); ++b) f.fitted_box_size_[b] = box_size(f.bounds_[b]);
  // What only fitting needed.
  f.trees_.clear();
  f.trees_.shrink_to_fit();
  return f;
}

RefitReport EdgeForest::refit(std::span<const ForestShapeInput> shapes) {
  const auto t0 = std::chrono::steady_clock::now();
  RefitReport report;
  if (fit_options_.empty()) {
    report.reason = "the forest was not fitted";
    return report;
  }
  if (!refit_input_matches(shapes, report)) return report;
  // The intersection curves of the moved surfaces, found beside the edges' and nodes' refit (they
  // read the meshes only) and appended after it.
  std::vector<CrossingSegment> crossings;
  IntersectionCurveStats crossing_stats;
  tbb::task_group crossings_task;
  if (options_.intersection_curves)
    crossings_task.run([&] { crossings = find_crossings(shapes, crossing_stats, &pair_cache_); });
  refit_edges(shapes, report);
  const NodeFitOptions& options = fit_options_.front();
  constexpr std::uint16_t kFitFlags = kNodeUnrejectable | kNodeBoxOnly | kNodeInherited | kNodeUsedLp;
  // Per node: 0 untouched, 1 refitted, 2 fitted anew (D failed), 3 fitted anew (the offsets failed);
  // and log(box growth) of the refitted ones. Summed in node order afterwards (deterministic).
  std::vector<std::uint8_t> outcome(shapes_nodes_end_, 0);
  std::vector<double> log_growth(shapes_nodes_end_, 0.0);
  tbb::enumerable_thread_specific<FitScratch> scratch;
  tbb::parallel_for(size_t(0), shapes_nodes_end_, [&](size_t i) {
    ForestNode& n = nodes_[i];
    if (n.bound < 0 || n.unrejectable()) return;  // an unrejectable node stays so: sound
    NodeBound& b = bounds_[size_t(n.bound)];
    FitScratch& sc = scratch.local();
    std::vector<Wedge>& wedges = sc.wedges;
    wedges.clear();
    for (int k = n.edge_begin; k < n.edge_end; ++k) wedges.push_back({edges_[size_t(k)].q0, edges_[size_t(k)].q1});
    const NodeRefit r = refit_node(wedges, n.box_only(), b);
    if (r == NodeRefit::Refitted) {
      outcome[i] = 1;
      const double s0 = fitted_box_size_[size_t(n.bound)], s1 = box_size(b);
      if (s0 > 0.0 && s1 > 0.0) log_growth[i] = std::log(s1 / s0);
      return;
    }
    // Fitted anew as at build, but with no parent to inherit from (a node with too few planes is
    // box-only, which is sound).
    const NodeFit fit = fit_range(edges_, n, nullptr, options, sc);
    n.flags = std::uint16_t((n.flags & ~kFitFlags) | fit.flags);
    b = fit.bound;
    fitted_box_size_[size_t(n.bound)] = box_size(b);
    outcome[i] = r == NodeRefit::BoxOnly ? 3 : 2;
  });
  double sum_log = 0.0;
  int growth_nodes = 0;
  for (size_t i = 0; i < shapes_nodes_end_; ++i) {
    if (outcome[i] == 0) continue;
    ++report.bounds;
    if (outcome[i] >= 2) ++report.refitted_fully;
    if (nodes_[i].box_only()) ++report.box_only;
    if (outcome[i] == 1) {
      sum_log += log_growth[i];
      ++growth_nodes;
    }
  }
  report.box_growth = growth_nodes ? std::exp(sum_log / growth_nodes) : 1.0;
  crossings_task.wait();
  if (options_.intersection_curves) {
    add_crossings(*this, shapes, std::move(crossings), options_);
    crossing_stats_ = crossing_stats;
    report.crossing_seconds = crossing_stats.seconds;
  }
  report.refitted = true;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

size_t EdgeForest::memory_bytes() const {
  return EdgeSet::memory_bytes() + bounds_.capacity() * sizeof(NodeBound) + fitted_box_size_.capacity() * sizeof(float);
}

}  // namespace qsil::edgetree
