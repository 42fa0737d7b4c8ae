#pragma once
/// @file edge_forest.h
/// The quadric edge forest [QSS 4.1-4.4; docs/architecture.md §5 "Tree", "Per node"]: an edge
/// set (edge_set.h) whose stored inner silhouette-tree nodes carry a fitted dual bound (node_fit.h):
/// the offset direction D, the dual box B_q and, for the `quadric` method, the bounding quadric
/// pair. `quadric-box` fits the dual box only (NodeFitOptions::fit_quadrics = false); the
/// baselines use the edge set without a forest.

#include "qsil/edgetree/edge_set.h"
#include "qsil/edgetree/node_fit.h"

#include <span>
#include <vector>

namespace qsil::edgetree {

/// Options of a forest build: the edge set's and the node fit's.
struct ForestOptions : EdgeSetOptions {
  NodeFitOptions fit;  ///< node fitting (min planes, quadrics on/off)
};

/// The edge forest over several shapes: an EdgeSet with fitted inner nodes.
class EdgeForest : public EdgeSet {
 public:
  EdgeForest() = default;

  /// EdgeSet::build, then fit() (the forest of every quadric method and of the tests).
  static EdgeForest build(std::span<const ForestShapeInput> shapes, const ForestOptions& options = {});

  /// Fits every stored inner node of `set`'s silhouette trees, per shape level by level (parents
  /// first: a node may inherit its parent's quadric), the nodes of a level in parallel with
  /// oneTBB; the discarded roots and the intermediate binary nodes are never fitted, nor the
  /// always-candidate trees. Thread count: the caller's TBB arena. The fit's flags go into the
  /// nodes and its counters into stats().
  static EdgeForest fit(EdgeSet set, const NodeFitOptions& options = {});

  /// Refits the forest to `shapes` after their vertices moved (the optimiser's case), instead of
  /// building it anew: the same shapes in the same order with the same triangles and crease
  /// rules, only the positions changed. Every edge moves and is reclassified; a tree edge now a
  /// crease is retired (Edge::retired) and, with every edge that stopped being flat, becomes an
  /// always-candidate crease; B_p and L_w are recomputed; each fitted node keeps its frame, offset
  /// direction and quadric Q_f and gets its dual box and offsets anew (refit_node), or is fitted
  /// anew where D no longer separates its planes; the intersection curves are found anew. The
  /// forest stays sound (no node rejects a point for which one of its edges is a silhouette);
  /// what degrades is tightness (RefitReport::box_growth). Nothing changes, and
  /// RefitReport::refitted is false with the reason, when the input is not the shapes built
  /// (`shapes` must then get a new build). Invalidates every pointer or reference into edges()
  /// and always_edges() (samplers, contour indices and primary edges are made anew after it).
  /// Thread count: the caller's TBB arena.
  RefitReport refit(std::span<const ForestShapeInput> shapes);

  /// Dual bounds of the fitted inner nodes (ForestNode::bound indexes this).
  const std::vector<NodeBound>& bounds() const { return bounds_; }
  /// Bytes of the forest's arrays (nodes, bounds, edges, roots).
  size_t memory_bytes() const;

 private:
  std::vector<NodeBound> bounds_;
  std::vector<NodeFitOptions> fit_options_;  ///< the options of the fit (one entry), for a refit's fits anew
  /// Per bound: the dual box's size (sum of its extents) when it was last fitted anew, the
  /// baseline of RefitReport::box_growth.
  std::vector<float> fitted_box_size_;
};

}  // namespace qsil::edgetree
