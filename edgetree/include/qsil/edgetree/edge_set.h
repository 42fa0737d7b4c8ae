#pragma once
/// @file edge_set.h
/// The scene's candidate edges [QSS 4.1; docs/architecture.md §5 "Edges", "Tree"]: per shape,
/// its edges classified (mesh_edges.h) into silhouette-tree candidates (convex, optionally
/// concave) and always-candidates (boundary, non-manifold, inconsistent, creases), each group
/// ordered by a top-down 4-wide binned-SAH hierarchy (each shape's root is discarded, so it
/// contributes up to four roots) whose nodes carry B_p and L_w only, no dual bound. Nodes live in
/// one flat array; a node's children are contiguous. The baselines (vsphere, uniform) use the
/// edges as they are, in the hierarchy's leaf order (so their tables and sorts see the forest's
/// order); EdgeForest (edge_forest.h) fits dual bounds for the quadric methods.

#include "qsil/check.h"
#include "qsil/edgetree/intersection_curves.h"
#include "qsil/edgetree/mesh_edges.h"
#include "qsil/math.h"
#include "qsil/scene.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace qsil::edgetree {

/// Flags of a hierarchy node (bit set). kNodeLeaf and kNodeAlways describe the topology (set by
/// EdgeSet::build); the others are set by fitting (node_fit.h).
enum NodeFlags : std::uint16_t {
  kNodeLeaf = 1,          ///< leaf: holds up to 4 edges, tested exactly per edge
  kNodeUnrejectable = 2,  ///< no offset direction: a silhouette for every point [QSS App. B]
  kNodeBoxOnly = 4,       ///< no usable quadric: the rejection test stops after the dual box
  kNodeInherited = 8,     ///< Q_f inherited from the parent (too few planes or failed fit)
  kNodeUsedLp = 16,       ///< D came from the LP [QSS Eq. 6] (a point, not a direction)
  kNodeAlways = 32,       ///< a node of an always-candidate tree: no rejection test, no dual bound
};

/// The edge record every edge set and sampler shares (the edge forest, the v-sphere tree, the
/// uniform tables): the mesh edge (vertex and face indices into its shape's mesh,
/// world planes q0/q1, length, exterior angle, class, shape index) plus its endpoint positions
/// (world frame, scene units); or a segment of an intersection curve (cls
/// EdgeClass::Intersection, `crossing` set; `shape` is then its crossing group's id, no shape of
/// the scene: EdgeSet::crossing_groups).
struct Edge : MeshEdge {
  Vec3 p0 = Vec3::Zero();  ///< position of v0
  Vec3 p1 = Vec3::Zero();  ///< position of v1
  /// A shading crease: the radiance may jump across it where both of its faces face the viewer
  /// (every non-flat edge of a flat-shaded shape; the concave edges of a smooth-shaded one, see
  /// CreaseSet).
  bool crease = false;
  /// A crease of a smooth-shaded shape (CreaseSet::Concave or All): seen from a point for which
  /// it is no silhouette, its radiance jumps only in the slivers where one face's shading normal
  /// and geometric normal disagree, which few paths find (docs/design-notes.md "Crease samples").
  bool smooth_crease = false;
  /// A silhouette-tree edge that a refit (EdgeForest::refit) found bent the other way: its
  /// copy among the always-candidates (a crease) stands for it. It stays in its tree (node
  /// bounds may cover more planes than needed: sound) but is a discontinuity for no point.
  bool retired = false;
  /// For a segment of an intersection curve: its crossing triangles, planes and how its ends
  /// move (owned by the EdgeSet, shared by its copies); null for a mesh edge.
  const CrossingSegment* crossing = nullptr;
};

/// The velocities of end `end` (0: p0, 1: p1) of mesh edge e (e.crossing null), by reference: its
/// vertex's (v0, v1), 3 x kMaxParameters, world units per unit theta (see edge_end_velocity).
inline const SceneVelocities::Block& mesh_edge_end_velocity(const Edge& e, int end, const SceneVelocities& velocities) {
  QSIL_DCHECK_MSG(!e.crossing, "mesh_edge_end_velocity of a segment of an intersection curve");
  return velocities.position[size_t(e.shape)][size_t(end ? e.v1 : e.v0)];
}
/// Not for a temporary SceneVelocities: the reference would outlive it.
const SceneVelocities::Block& mesh_edge_end_velocity(const Edge& e, int end,
                                                     const SceneVelocities&& velocities) = delete;

/// The velocity of end `end` (0: p0, 1: p1) of edge e for every parameter (3 x kMaxParameters,
/// world units per unit theta): its vertex's (v0, v1) for a mesh edge, crossing_end_velocity for
/// a segment of an intersection curve. The velocity of the edge point at t is (1 - t) times that
/// of end 0 plus t times that of end 1.
inline SceneVelocities::Block edge_end_velocity(const Edge& e, int end, const SceneVelocities& velocities) {
  if (e.crossing) return crossing_end_velocity(e.crossing->ends[size_t(end)], velocities);
  return mesh_edge_end_velocity(e, end, velocities);
}

/// True iff the radiance seen from p can jump across edge e: a silhouette or boundary edge
/// (edge_is_silhouette), or a crease (its shading jumps there whether or not it is a
/// silhouette). Edge samplers return only such edges.
inline bool is_discontinuity(const Edge& e, const Vec3& p) {
  return !e.retired && (e.crease || edge_is_silhouette(e, p));
}

/// Weight of an always-candidate edge in its tree's L_w (units * rad): a crease bounds a jump
/// that grows with its bend angle (length * angle, as tree edges); a boundary, non-manifold or
/// inconsistent edge bounds a jump of the full radiance, like a silhouette of angle pi.
inline double always_edge_weight(const Edge& e) { return e.length * (e.crease ? e.angle : kPi); }

/// A node of the edge set's hierarchy (and of the forest fitted over it). Inner nodes: children are nodes [first, first
/// + count) (1..4 of them). Leaves (kNodeLeaf): edges [first, first + count) (1..4 of them) of EdgeSet::edges(), or of
/// EdgeSet::always_edges() for a node of an always-candidate tree (kNodeAlways). Every node covers the contiguous edge
/// range [edge_begin, edge_end) of the same array.
struct ForestNode {
  Box3 bp;                  ///< primal box B_p of the patch's edge endpoints (world, scene units)
  double lw = 0.0;          ///< L_w = sum of edge length * exterior dihedral angle (units * rad);
                            ///< always_edge_weight() for always-candidate trees
  double lw_smooth = 0.0;   ///< the part of lw from concave smooth creases (Edge::smooth_crease;
                            ///< a twosided smooth shape's convex creases, often its silhouettes, not)
  int first = 0;            ///< first child (inner) or first edge (leaf)
  int count = 0;            ///< number of children (inner) or edges (leaf)
  int edge_begin = 0;       ///< first edge of the subtree in edges() (always_edges() if kNodeAlways)
  int edge_end = 0;         ///< one past the last edge of the subtree
  int bound = -1;           ///< index into EdgeForest::bounds() (fitted inner nodes), else -1
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

/// Which non-flat edges of a shape are shading creases (Edge::crease), i.e. where the
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

/// Options of the edge set: edge culling, the hierarchy and intersection curves.
struct EdgeSetOptions {
  EdgeOptions edges;     ///< edge culling (keep_concave)
  /// Find the intersection curves between the shapes and within each (find_intersection_curves)
  /// and make their segments always-candidates. Off: a scene whose surfaces cross misses those
  /// discontinuities (the A/B switch of the tests and comparisons).
  bool intersection_curves = true;
  int leaf_size = 4;     ///< maximum edges per leaf (1..4)
  int sah_buckets = 10;  ///< SAH buckets along the largest centroid axis [QSS 4.1]
  /// A shape's always-candidate edges get a tree of their own (box-only nodes, no rejection)
  /// when there are more than this many; fewer stay loose top-level candidates.
  int always_tree_min_edges = 8;
};

/// Statistics of one shape's hierarchy (for `qsil forest --stats`, the benchmark and the
/// estimators' set-up reports). The fit counters stay 0 in an edge set that was not fitted.
struct ForestShapeStats {
  int shape = 0;
  std::array<int, kEdgeClassCount> edge_counts{};  ///< per EdgeClass
  int edges_total = 0;               ///< unique undirected edges of the mesh
  int edges_kept = 0;                ///< tree candidates
  int edges_always = 0;              ///< always-candidate edges (boundary, non-manifold, inconsistent, creases)
  int creases = 0;                   ///< of which creases
  int always_nodes = 0;              ///< nodes of the shape's always-candidate tree (0: its edges are loose)
  int nodes = 0;                     ///< stored nodes (inner + leaves; the discarded root not counted)
  int inner_nodes = 0;
  int leaves = 0;
  int roots = 0;               ///< forest roots contributed (<= 4)
  int depth = 0;               ///< maximum node depth + 1 (levels below the discarded root)
  int fitted = 0;              ///< inner nodes with a fitted dual bound (EdgeForest)
  int quadrics = 0;            ///< ...of which carry a bounding quadric pair (neither unrejectable nor box-only)
  int unrejectable = 0;        ///< inner nodes marked unrejectable
  int box_only = 0;            ///< inner nodes without a quadric
  int inherited = 0;           ///< inner nodes with the parent's Q_f
  int used_lp = 0;             ///< inner nodes whose D came from the LP
  double build_seconds = 0.0;  ///< wall time of edge extraction and topology (+ fitting in a forest)
};

/// The segments of the intersection curves between two shapes (or within one), which the edge
/// set keeps together: always-candidates whose Edge::shape (and whose always-candidate
/// tree's ForestNode::shape) is `id`, one past the largest input shape index plus the group's
/// position in EdgeSet::crossing_groups(). They are eligible where either shape is
/// (SilhouetteQuery::eligible is extended with their ids by the boundary term's set-up).
struct CrossingGroup {
  int id = 0;                  ///< the group's index in eligibility vectors and Edge::shape
  int shape0 = 0, shape1 = 0;  ///< the two shapes, shape0 <= shape1 (equal: a self-intersection)
  int segments = 0;            ///< number of its segments
};

/// Box growth (RefitReport::box_growth) beyond which a refit forest should be built anew: at 1.1
/// the false-accept share of the rejection test is about 15 % (relative) above a new build's on
/// spot, bunny and an 82k-triangle blob (tools/bench/bench_refit;
/// docs/experiments/2026-11-25-refit.md).
inline constexpr double kRefitMaxBoxGrowth = 1.1;
/// Share of edges promoted to always-candidate creases (retired + unflattened) beyond which a
/// refit forest should be built anew: each is a candidate for every shading point, where a
/// build would put a convex one back in a silhouette tree (a teapot's flat edges all bend at the
/// first step: same record).
inline constexpr double kRefitMaxPromotedShare = 0.01;

/// What a refit (EdgeForest::refit) did, or why it could not.
struct RefitReport {
  bool refitted = false;  ///< false: nothing changed, rebuild (`reason` says why)
  std::string reason;     ///< why not, naming the shape ("shape 2: triangles changed")
  int edges = 0;          ///< mesh edges updated (tree and always-candidates)
  /// Silhouette-tree edges now bent the other way (concave on a shape whose concave edges are
  /// creases), retired from their tree and added to the always-candidates as creases.
  int retired = 0;
  /// Edges in no array at build time (flat, or concave and culled) that now bend (or turned
  /// convex), added to the always-candidates as creases.
  int unflattened = 0;
  int bounds = 0;         ///< fitted inner nodes whose dual bound was refitted (D, A, Q_f kept)
  int refitted_fully = 0; ///< ...of which fitted anew (D no longer separated their planes, or
                          ///< the offsets failed)
  int box_only = 0;       ///< ...of which have no quadric pair after it
  /// Geometric mean over refitted nodes of (dual-box size now) / (dual-box size when fitted),
  /// the size the sum of the box's extents: how much looser the refit bounds are.
  double box_growth = 1.0;
  double seconds = 0.0;   ///< wall time, intersection curves included
  /// Wall time of finding the intersection curves anew, beside the rest of the refit (so it
  /// overlaps the other work in `seconds`).
  double crossing_seconds = 0.0;
  /// Whether the refit forest is loose enough that a build anew pays (kRefitMaxBoxGrowth,
  /// kRefitMaxPromotedShare), or the refit did not happen.
  bool rebuild_advised() const {
    return !refitted || box_growth > kRefitMaxBoxGrowth ||
           double(retired + unflattened) > kRefitMaxPromotedShare * double(std::max(edges, 1));
  }
};

/// The candidate edges of several shapes and their SAH hierarchy (see the file comment).
class EdgeSet {
 public:
  EdgeSet() = default;

  /// Builds the edge set: edge extraction and classification per shape, then the top-down 4-wide
  /// SAH topology of its silhouette-tree edges and of its always-candidate edges (three binary
  /// splits per level, `sah_buckets` buckets along the largest axis of the edge centroids' box,
  /// cost = area * count), B_p and L_w of every node (in parallel with oneTBB). Fits nothing.
  /// The intersection curves (EdgeSetOptions::intersection_curves) are found beside the trees,
  /// in a task of their own, and appended after them; the result does not depend on the thread
  /// count or on which finished first.
  static EdgeSet build(std::span<const ForestShapeInput> shapes, const EdgeSetOptions& options = {});

  /// Every node, flat (a node's children are contiguous), silhouette and always-candidate trees.
  const std::vector<ForestNode>& nodes() const { return nodes_; }
  /// Node i (checked in debug builds).
  const ForestNode& node(int i) const {
    QSIL_DCHECK(i >= 0 && i < int(nodes_.size()));
    return nodes_[size_t(i)];
  }
  /// Roots of the silhouette trees (the children of each shape's discarded root), grouped by shape.
  const std::vector<int>& roots() const { return roots_; }
  /// Roots of the always-candidate trees (kNodeAlways; the children of each discarded root).
  const std::vector<int>& always_roots() const { return always_roots_; }
  /// Indices into always_edges() of the edges in no always-candidate tree (loose top-level
  /// candidates, e.g. the four outline edges of a rectangle).
  const std::vector<int>& loose_always_edges() const { return loose_always_edges_; }
  /// Tree edges in leaf order (a leaf's edges are contiguous), grouped by shape.
  const std::vector<Edge>& edges() const { return edges_; }
  /// Always-candidate edges (boundary, non-manifold, inconsistently oriented, creases, and the
  /// segments of intersection curves, group by group after every shape's): a possible
  /// discontinuity for every shading point, never in a silhouette tree; those of a shape (or
  /// crossing group) with more than EdgeSetOptions::always_tree_min_edges are in its
  /// always-candidate tree (leaf order), the others are loose_always_edges().
  const std::vector<Edge>& always_edges() const { return always_; }
  /// Children of an inner node as a node-index range [first, first+count); empty for a leaf.
  std::span<const ForestNode> children(int i) const {
    const ForestNode& n = node(i);
    if (n.is_leaf()) return {};
    return {nodes_.data() + n.first, size_t(n.count)};
  }
  /// Edges of a leaf (empty for an inner node), from edges() or, for an always-candidate tree's
  /// leaf, from always_edges().
  std::span<const Edge> leaf_edges(int i) const {
    const ForestNode& n = node(i);
    if (!n.is_leaf()) return {};
    return {(n.always() ? always_.data() : edges_.data()) + n.first, size_t(n.count)};
  }
  /// Edges below node i (its edge range in edges() or always_edges()).
  std::span<const Edge> node_edges(int i) const {
    const ForestNode& n = node(i);
    return {(n.always() ? always_.data() : edges_.data()) + n.edge_begin, size_t(n.edge_end - n.edge_begin)};
  }
  /// Per-shape statistics of the build, in input order (a refit leaves them as built; its own
  /// counts are in RefitReport).
  const std::vector<ForestShapeStats>& stats() const { return stats_; }
  /// The crossing groups (intersection curves between a pair of shapes), by (shape0, shape1);
  /// empty when no surfaces cross or EdgeSetOptions::intersection_curves is off.
  const std::vector<CrossingGroup>& crossing_groups() const { return crossing_groups_; }
  /// Every segment of the intersection curves (the always-candidate edges of the groups point
  /// into this array), or empty.
  std::span<const CrossingSegment> crossings() const {
    return crossings_ ? std::span<const CrossingSegment>(*crossings_) : std::span<const CrossingSegment>();
  }
  /// What finding the intersection curves did (zeros when off). Its seconds are wall time while
  /// the trees were built beside it (build()), so they overlap the shapes' build_seconds.
  const IntersectionCurveStats& crossing_stats() const { return crossing_stats_; }
  /// Bytes of the arrays (nodes, edges, roots, intersection-curve segments, the refits' pair cache).
  size_t memory_bytes() const;

 protected:
  /// What fitting a shape's silhouette tree needs beyond its edges: its node levels, parents
  /// first (each a node range [first, second)).
  struct ShapeTree {
    std::vector<std::pair<int, int>> levels;
  };
  std::vector<ForestNode> nodes_;
  std::vector<int> roots_;
  std::vector<int> always_roots_;
  std::vector<int> loose_always_edges_;
  std::vector<Edge> edges_;
  std::vector<Edge> always_;
  /// The intersection curves of `shapes` (find_intersection_curves over their meshes, with
  /// `cache` if given), its statistics into `stats`. Reads the meshes only: build() runs it beside
  /// the shapes' trees.
  static std::vector<CrossingSegment> find_crossings(std::span<const ForestShapeInput> shapes,
                                                     IntersectionCurveStats& stats,
                                                     CandidatePairCache* cache = nullptr);
  /// Appends `segments` (find_crossings') to `f` as always-candidates, one crossing group per
  /// pair of shapes (a tree per group when it has more than opt.always_tree_min_edges segments).
  static void add_crossings(EdgeSet& f, std::span<const ForestShapeInput> shapes, std::vector<CrossingSegment> segments,
                            const EdgeSetOptions& opt);
  std::vector<ForestShapeStats> stats_;
  std::vector<ShapeTree> trees_;  ///< per input shape
  /// A shape as built, what a refit checks its input against: vertex and triangle counts, a hash
  /// of the triangles (a refit needs the same topology) and the crease rule.
  struct ShapeRecord {
    int shape = 0;
    int vertices = 0, triangles = 0;
    std::uint64_t triangle_hash = 0;
    bool face_normals = false;
    CreaseSet creases = CreaseSet::None;
  };
  std::vector<ShapeRecord> shape_records_;
  /// An edge in no array when built (flat, or concave and culled: CreaseSet::None without
  /// keep_concave), as a refit needs it to find those that bend or turn convex.
  struct FlatEdge {
    int v0, v1, f0, f1, shape;
  };
  std::vector<FlatEdge> flat_edges_;
  EdgeSetOptions options_;  ///< the options of the build (a refit finds crossings the same way)
  /// Array sizes after the shapes' own edges and trees: a refit truncates to them, then adds its
  /// promoted creases and the intersection curves anew.
  size_t shapes_nodes_end_ = 0, shapes_always_end_ = 0, shapes_always_roots_end_ = 0, shapes_loose_end_ = 0;
  /// Whether `shapes` are the shapes built (shape_records_: the same places, vertex and triangle
  /// counts, triangles and crease rules), the condition of a refit; else false with
  /// report.reason set.
  bool refit_input_matches(std::span<const ForestShapeInput> shapes, RefitReport& report) const;
  /// The edge half of EdgeForest::refit, for input refit_input_matches accepted: moves every edge
  /// to the new positions and reclassifies it, retires tree edges now concave creases and
  /// promotes them and the edges that stopped being flat to always-candidate creases, and
  /// recomputes B_p and L_w of the shapes' nodes. Drops the intersection curves: the caller finds
  /// them anew (find_crossings, add_crossings).
  void refit_edges(std::span<const ForestShapeInput> shapes, RefitReport& report);
  std::vector<CrossingGroup> crossing_groups_;
  std::shared_ptr<const std::vector<CrossingSegment>> crossings_;  ///< shared by copies: edges point into it
  IntersectionCurveStats crossing_stats_;
  /// The broad phase's pairs for the refits' intersection curves: filled by the first refit
  /// (a build that is never refitted keeps none), read by the next while the vertices stay near.
  CandidatePairCache pair_cache_;
};

}  // namespace qsil::edgetree
