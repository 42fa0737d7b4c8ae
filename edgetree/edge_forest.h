#pragma once
/// @file edge_forest.h
/// The quadric edge forest [QSS 4.1; docs/architecture.md §5 "Tree"]: one 4-wide tree per shape over its
/// candidate (convex, optionally concave) edges, built top-down with binned SAH splits; each
/// shape's root is discarded so it contributes up to four forest roots. Inner nodes carry the
/// dual bound of node_fit.h, the primal box B_p and the weighted length L_w; leaves hold up to 4
/// edges. Nodes live in one flat array; children of a node are contiguous.

#include "edgetree/mesh_edges.h"
#include "edgetree/node_fit.h"
#include "qsil/math.h"
#include "qsil/scene.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace qsil::edgetree {

/// An edge stored in the forest: the mesh edge (vertex and face indices into its shape's mesh,
/// world planes q0/q1, length, exterior angle, class, shape index) plus its endpoint positions
/// (world frame, scene units).
struct ForestEdge : MeshEdge {
  Vec3 p0 = Vec3::Zero();  ///< position of v0
  Vec3 p1 = Vec3::Zero();  ///< position of v1
  bool crease = false;     ///< a non-flat edge of a flat-shaded (face_normals) shape
};

/// True iff the radiance seen from p can jump across edge e: a silhouette or boundary edge
/// (edge_is_silhouette), or a crease of a flat-shaded shape (its shading jumps there whether or
/// not it is a silhouette). Edge samplers return only such edges.
inline bool is_discontinuity(const ForestEdge& e, const Vec3& p) { return e.crease || edge_is_silhouette(e, p); }

/// A node of the forest. Inner nodes: children are nodes [first, first + count) (1..4 of them).
/// Leaves (kNodeLeaf): edges [first, first + count) of EdgeForest::edges() (1..4 of them).
/// Every node covers the contiguous edge range [edge_begin, edge_end).
struct ForestNode {
  Box3 bp;                  ///< primal box B_p of the patch's edge endpoints (world, scene units)
  double lw = 0.0;          ///< L_w = sum of edge length * exterior dihedral angle (units * rad)
  int first = 0;            ///< first child (inner) or first edge (leaf)
  int count = 0;            ///< number of children (inner) or edges (leaf)
  int edge_begin = 0;       ///< first edge of the subtree in EdgeForest::edges()
  int edge_end = 0;         ///< one past the last edge of the subtree
  int bound = -1;           ///< index into EdgeForest::bounds() (inner nodes), else -1
  int parent = -1;          ///< parent node, -1 for forest roots
  int shape = 0;            ///< shape index
  std::uint16_t flags = 0;  ///< NodeFlags
  std::uint16_t depth = 0;  ///< 0 for forest roots
  bool is_leaf() const { return flags & kNodeLeaf; }
  bool unrejectable() const { return flags & kNodeUnrejectable; }
  bool box_only() const { return flags & kNodeBoxOnly; }
};

/// One input shape of the forest.
struct ForestShapeInput {
  const TriangleMesh* mesh = nullptr;  ///< welded mesh, world frame
  int shape = 0;                       ///< the shape's index (kept in every edge and node)
  /// Flat shading (Mitsuba's face_normals): the radiance jumps across every non-flat edge, so
  /// every convex and concave edge is an always-candidate (a crease) and the shape has no tree.
  bool face_normals = false;
};

/// Options of the forest build.
struct ForestOptions {
  EdgeOptions edges;         ///< edge culling (keep_concave)
  NodeFitOptions fit;        ///< node fitting (min planes, quadrics on/off)
  int leaf_size = 4;         ///< maximum edges per leaf (1..4)
  int sah_buckets = 10;      ///< SAH buckets along the largest centroid axis [QSS 4.1]
};

/// Statistics of one shape's tree (for `qsil forest --stats` and the benchmark).
struct ForestShapeStats {
  int shape = 0;
  std::array<int, 6> edge_counts{};  ///< per EdgeClass
  int edges_total = 0;       ///< unique undirected edges of the mesh
  int edges_kept = 0;        ///< tree candidates
  int edges_always = 0;      ///< always-candidate edges (boundary, non-manifold, inconsistent)
  int nodes = 0;             ///< stored nodes (inner + leaves; the discarded root not counted)
  int inner_nodes = 0;
  int leaves = 0;
  int roots = 0;             ///< forest roots contributed (<= 4)
  int unrejectable = 0;      ///< inner nodes marked unrejectable
  int box_only = 0;          ///< inner nodes without a quadric
  int inherited = 0;         ///< inner nodes with the parent's Q_f
  int used_lp = 0;           ///< inner nodes whose D came from the LP
  int depth = 0;             ///< maximum node depth + 1 (levels below the discarded root)
  double build_seconds = 0.0;///< wall time of edge extraction, topology and fitting
};

/// The edge forest over several shapes.
class EdgeForest {
 public:
  EdgeForest() = default;

  /// Builds the forest: edge extraction and classification per shape, top-down 4-wide SAH
  /// topology (three binary splits per level, 10 buckets along the largest axis of the edge
  /// centroids' box, cost = area * count), then fitting of every stored inner node in parallel
  /// with oneTBB, level by level (a node may inherit its parent's quadric). The discarded roots
  /// and the intermediate binary nodes are never fitted. Thread count: the caller's TBB arena.
  static EdgeForest build(std::span<const ForestShapeInput> shapes,
                          const ForestOptions& options = {});

  const std::vector<ForestNode>& nodes() const { return nodes_; }
  const ForestNode& node(int i) const { return nodes_[i]; }
  /// Forest roots (the children of each shape's discarded root), grouped by shape.
  const std::vector<int>& roots() const { return roots_; }
  /// Tree edges in leaf order (a leaf's edges are contiguous).
  const std::vector<ForestEdge>& edges() const { return edges_; }
  /// Always-candidate edges (boundary, non-manifold, inconsistently oriented): a discontinuity
  /// for every shading point; not in any tree.
  const std::vector<ForestEdge>& always_edges() const { return always_; }
  /// Dual bounds of the fitted inner nodes (ForestNode::bound indexes this).
  const std::vector<NodeBound>& bounds() const { return bounds_; }
  /// Children of an inner node as a node-index range [first, first+count); empty for a leaf.
  std::span<const ForestNode> children(int i) const {
    const ForestNode& n = nodes_[i];
    if (n.is_leaf()) return {};
    return {nodes_.data() + n.first, size_t(n.count)};
  }
  /// Edges of a leaf (empty for an inner node).
  std::span<const ForestEdge> leaf_edges(int i) const {
    const ForestNode& n = nodes_[i];
    if (!n.is_leaf()) return {};
    return {edges_.data() + n.first, size_t(n.count)};
  }
  /// Per-shape statistics, in input order.
  const std::vector<ForestShapeStats>& stats() const { return stats_; }
  /// Bytes of the forest's arrays (nodes, bounds, edges, roots).
  size_t memory_bytes() const;

 private:
  std::vector<ForestNode> nodes_;
  std::vector<int> roots_;
  std::vector<ForestEdge> edges_;
  std::vector<ForestEdge> always_;
  std::vector<NodeBound> bounds_;
  std::vector<ForestShapeStats> stats_;
};

}  // namespace qsil::edgetree
