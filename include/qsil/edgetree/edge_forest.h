#pragma once
/// @file edge_forest.h
/// The quadric edge forest [QSS 4.1; docs/architecture.md §5 "Tree"]: one 4-wide tree per shape over its
/// candidate (convex, optionally concave) edges, built top-down with binned SAH splits; each
/// shape's root is discarded so it contributes up to four forest roots. Inner nodes carry the
/// dual bound of node_fit.h, the primal box B_p and the weighted length L_w; leaves hold up to 4
/// edges. Nodes live in one flat array; children of a node are contiguous.

#include "qsil/edgetree/mesh_edges.h"
#include "qsil/edgetree/node_fit.h"
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
  /// A shading crease: the radiance may jump across it where both of its faces face the viewer
  /// (every non-flat edge of a flat-shaded shape; the concave edges of a smooth-shaded one, see
  /// CreaseSet).
  bool crease = false;
};

/// True iff the radiance seen from p can jump across edge e: a silhouette or boundary edge
/// (edge_is_silhouette), or a crease (its shading jumps there whether or not it is a
/// silhouette). Edge samplers return only such edges.
inline bool is_discontinuity(const ForestEdge& e, const Vec3& p) { return e.crease || edge_is_silhouette(e, p); }

/// Weight of an always-candidate edge in its tree's L_w (units * rad): a crease bounds a jump
/// that grows with its bend angle (length * angle, as tree edges); a boundary, non-manifold or
/// inconsistent edge bounds a jump of the full radiance, like a silhouette of angle pi.
inline double always_edge_weight(const ForestEdge& e) { return e.length * (e.crease ? e.angle : kPi); }

/// A node of the forest. Inner nodes: children are nodes [first, first + count) (1..4 of them).
/// Leaves (kNodeLeaf): edges [first, first + count) (1..4 of them) of EdgeForest::edges(), or
/// of EdgeForest::always_edges() for a node of an always-candidate tree (kNodeAlways). Every
/// node covers the contiguous edge range [edge_begin, edge_end) of the same array.
struct ForestNode {
  Box3 bp;                  ///< primal box B_p of the patch's edge endpoints (world, scene units)
  double lw = 0.0;          ///< L_w = sum of edge length * exterior dihedral angle (units * rad);
                            ///< always_edge_weight() for always-candidate trees
  int first = 0;            ///< first child (inner) or first edge (leaf)
  int count = 0;            ///< number of children (inner) or edges (leaf)
  int edge_begin = 0;       ///< first edge of the subtree in edges() (always_edges() if kNodeAlways)
  int edge_end = 0;         ///< one past the last edge of the subtree
  int bound = -1;           ///< index into EdgeForest::bounds() (inner nodes), else -1
  int parent = -1;          ///< parent node, -1 for forest roots
  int shape = 0;            ///< shape index
  std::uint16_t flags = 0;  ///< NodeFlags
  std::uint16_t depth = 0;  ///< 0 for forest roots
  bool is_leaf() const { return flags & kNodeLeaf; }
  bool unrejectable() const { return flags & kNodeUnrejectable; }
  bool box_only() const { return flags & kNodeBoxOnly; }
  /// A node of an always-candidate tree: every edge below is a candidate for every shading point
  /// (no rejection test); only its box and L_w steer the traversal.
  bool always() const { return flags & kNodeAlways; }
};

/// Which non-flat edges of a shape are shading creases (ForestEdge::crease), i.e. where the
/// radiance leaving the surface jumps although no silhouette is there:
/// - All: every convex and concave edge. Flat shading (face_normals): the normal jumps; and a
///   smooth-shaded twosided shape: a sliver ray from one face meets the back of its neighbour,
///   which scatters, while from the neighbour the same direction leaves into the open.
/// - Concave: the concave edges of a smooth-shaded one-sided shape. Sliver rays (above the
///   shading horizon, below the face's plane) pass through back faces, which makes the radiance
///   continuous across convex edges; at a concave edge the same direction seen from the other
///   face meets this face from the front (docs/design-notes.md "Smooth shading").
/// - None: no creases (tests of the silhouette tree alone).
enum class CreaseSet { None, Concave, All };

/// One input shape of the forest.
struct ForestShapeInput {
  const TriangleMesh* mesh = nullptr;  ///< welded mesh, world frame
  int shape = 0;                       ///< the shape's index (kept in every edge and node)
  /// Flat shading (Mitsuba's face_normals): every convex and concave edge is a crease, and the
  /// shape has no silhouette tree (the crease branch of the boundary term covers silhouettes).
  /// Implies creases = CreaseSet::All.
  bool face_normals = false;
  /// The creases of a smooth-shaded shape (see CreaseSet): always-candidates, not tree edges.
  CreaseSet creases = CreaseSet::None;
};

/// The forest inputs of every shape of a scene, as the boundary term needs them: a shape with
/// flat shading (face_normals, or no vertex normals) has every non-flat edge as a crease; a
/// smooth-shaded shape its concave edges (CreaseSet::Concave), or all of them when its BSDF is
/// twosided (CreaseSet::All). The inputs point into `scene`, which must outlive them.
std::vector<ForestShapeInput> forest_inputs(const Scene& scene);

/// Options of the forest build.
struct ForestOptions {
  EdgeOptions edges;         ///< edge culling (keep_concave)
  NodeFitOptions fit;        ///< node fitting (min planes, quadrics on/off)
  int leaf_size = 4;         ///< maximum edges per leaf (1..4)
  int sah_buckets = 10;      ///< SAH buckets along the largest centroid axis [QSS 4.1]
  /// A shape's always-candidate edges get a tree of their own (box-only nodes, no rejection)
  /// when there are more than this many; fewer stay loose top-level candidates.
  int always_tree_min_edges = 8;
};

/// Statistics of one shape's tree (for `qsil forest --stats` and the benchmark).
struct ForestShapeStats {
  int shape = 0;
  std::array<int, 6> edge_counts{};  ///< per EdgeClass
  int edges_total = 0;       ///< unique undirected edges of the mesh
  int edges_kept = 0;        ///< tree candidates
  int edges_always = 0;      ///< always-candidate edges (boundary, non-manifold, inconsistent, creases)
  int creases = 0;           ///< of which creases
  int always_nodes = 0;      ///< nodes of the shape's always-candidate tree (0: its edges are loose)
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
  /// Roots of the always-candidate trees (kNodeAlways; the children of each discarded root).
  const std::vector<int>& always_roots() const { return always_roots_; }
  /// Indices into always_edges() of the edges in no always-candidate tree (loose top-level
  /// candidates, e.g. the four outline edges of a rectangle).
  const std::vector<int>& loose_always() const { return loose_always_; }
  /// Tree edges in leaf order (a leaf's edges are contiguous).
  const std::vector<ForestEdge>& edges() const { return edges_; }
  /// Always-candidate edges (boundary, non-manifold, inconsistently oriented, creases): a
  /// possible discontinuity for every shading point, never in a silhouette tree; those of a shape
  /// with more than ForestOptions::always_tree_min_edges are in its always-candidate tree (leaf
  /// order), the others are loose_always().
  const std::vector<ForestEdge>& always_edges() const { return always_; }
  /// Dual bounds of the fitted inner nodes (ForestNode::bound indexes this).
  const std::vector<NodeBound>& bounds() const { return bounds_; }
  /// Children of an inner node as a node-index range [first, first+count); empty for a leaf.
  std::span<const ForestNode> children(int i) const {
    const ForestNode& n = nodes_[i];
    if (n.is_leaf()) return {};
    return {nodes_.data() + n.first, size_t(n.count)};
  }
  /// Edges of a leaf (empty for an inner node), from edges() or, for an always-candidate tree's
  /// leaf, from always_edges().
  std::span<const ForestEdge> leaf_edges(int i) const {
    const ForestNode& n = nodes_[i];
    if (!n.is_leaf()) return {};
    return {(n.always() ? always_.data() : edges_.data()) + n.first, size_t(n.count)};
  }
  /// Edges below node i (its edge range in edges() or always_edges()).
  std::span<const ForestEdge> node_edges(int i) const {
    const ForestNode& n = nodes_[i];
    return {(n.always() ? always_.data() : edges_.data()) + n.edge_begin, size_t(n.edge_end - n.edge_begin)};
  }
  /// Per-shape statistics, in input order.
  const std::vector<ForestShapeStats>& stats() const { return stats_; }
  /// Bytes of the forest's arrays (nodes, bounds, edges, roots).
  size_t memory_bytes() const;

 private:
  std::vector<ForestNode> nodes_;
  std::vector<int> roots_;
  std::vector<int> always_roots_;
  std::vector<int> loose_always_;
  std::vector<ForestEdge> edges_;
  std::vector<ForestEdge> always_;
  std::vector<NodeBound> bounds_;
  std::vector<ForestShapeStats> stats_;
};

}  // namespace qsil::edgetree
