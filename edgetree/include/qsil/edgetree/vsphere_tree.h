#pragma once
/// @file vsphere_tree.h
/// The edge hierarchy of Li (2019) as used in redner: a binary BVH over edges with the v-sphere
/// rejection test in Hough space [QSS Sec. 2.3, Appendix F; Olson and Zhang 2006; docs/architecture.md §7].
///
/// Hough space. Fix a Hough origin o (the camera centre in a render). A plane with unit normal n
/// through x0 maps to the point h = n (n.(x0 - o)) = d n, the foot of the perpendicular from o
/// (relative to o; d is the signed distance of the plane from o). For a world plane
/// q = [n, -n.x0] (docs/architecture.md §3) that is h = -n (q.[o,1]).
/// For a shading point p let V = p - o. The v-sphere is the sphere with centre V/2 and radius
/// |V|/2; with g(h) = |h - V/2|^2 - |V|^2/4 = |h|^2 - h.V one finds g(h) = -d (q.[p,1]). For an edge
/// that is NOT a silhouette from o, d0 d1 > 0, so the edge is a silhouette for p iff
/// g(h0) g(h1) <= 0: then g vanishes somewhere on the segment [h0, h1] (continuity), i.e. the
/// segment meets the HOLLOW v-sphere, and so does any convex set that contains both endpoints,
/// e.g. the node's Hough box B_h. Hence the sound test: reject iff the hollow sphere misses the
/// solid box, i.e. min_{B_h} g > 0 or max_{B_h} g < 0, with min/max g = (min/max distance of B_h
/// to V/2)^2 - r^2. redner's original code tests a SOLID sphere (reject iff min g > 0 only): also
/// sound, but it accepts every box inside the sphere ([QSS] App. F; VSphereTest::Solid).
/// Edges that ARE silhouettes from o (d0 d1 <= 0) break the argument; they go into a plain
/// spatial BVH that is never rejected (docs/architecture.md §7).
///
/// The tree (VSphereTree::build): per shape, the shape's tree edges of the quadric forest are
/// split into the o-silhouette edges (plain 3D BVH over edge midpoints) and the others (6D BVH
/// over the point (edge midpoint, midpoint of h0 and h1)). Both are linear BVHs as in redner:
/// points normalised to the shape's bounds, Morton codes (6 x 10 bits, resp. 3 x 21 bits), sorted,
/// and split recursively at the highest differing bit (at the middle when all codes are equal).
/// Leaves hold one edge. Per-shape trees (redner builds one over all shapes) let the sampler
/// skip ineligible shapes at the top, as the quadric forest does.
///
/// Units: positions in scene units (world frame), Hough points in scene units relative to o.

#include "qsil/edgetree/edge_set.h"
#include "qsil/math.h"

#include <cstdint>
#include <vector>

namespace qsil::edgetree {

/// Relative tolerance of the v-sphere test: a margin of kVSphereTol times the magnitude of the
/// compared quantities counts as touching, i.e. accept (soundness under rounding).
inline constexpr double kVSphereTol = 1e-9;

/// Which v-sphere test a node runs (the `--boundary` methods `vsphere` and `vsphere-solid`).
enum class VSphereTest {
  Hollow,  ///< the hollow v-sphere vs the solid box, [QSS] App. F (the corrected test)
  Solid,   ///< the solid v-sphere, redner's original
};

/// Hough point of the world plane q = [n, -n.x0] (unit n) for the origin o: h = -n (q.[o,1])
/// (scene units, relative to o).
Vec3 hough_point(const Vec4& q, const Vec3& o);

/// The v-sphere test of a Hough box for the shading point p (world) and the Hough origin o, with
/// `test` (VSphereTest).
/// `world_scale` is the largest absolute world coordinate of the edges the box bounds (it scales
/// the rounding tolerance, together with |p|, |o| and the box). Returns false only when no plane
/// pair with Hough points in the box (and d0 d1 > 0) can be a silhouette for p: see the file
/// comment. An empty box is rejected.
bool vsphere_box_may_have_silhouette(const Box3& hough_box, double world_scale, const Vec3& p, const Vec3& o,
                                     VSphereTest test);

/// A node of the v-sphere tree. Inner nodes have two children; leaves hold one edge.
struct VSphereNode {
  Box3 bp;                  ///< spatial box of the edges' endpoints (world, scene units)
  Box3 bh;                  ///< Hough box of the face planes (relative to o); empty in plain trees
  double lw = 0.0;          ///< sum of edge length * exterior dihedral angle (units * rad)
  int child[2] = {-1, -1};  ///< children (inner nodes)
  int edge = -1;            ///< leaf: index into VSphereTree::edges(); -1 for inner nodes
  int shape = 0;            ///< shape index
  bool hough = false;       ///< in a 6D (v-sphere tested) tree; false: plain tree, never rejected
  bool is_leaf() const { return edge >= 0; }
};

/// A root of the v-sphere tree (one or two per shape).
struct VSphereRoot {
  int node = -1;
  int shape = 0;
  bool hough = false;  ///< a 6D root (edges that are not silhouettes from o)
};

/// Li's (2019) Hough-space edge tree over the tree edges of an edge set (the same
/// candidate edges: convex, plus concave ones where the forest keeps them) and its creases (in
/// the plain, untested part: a crease is a candidate for every point). The other
/// always-candidate (boundary) edges are not in it: samplers handle them at the top level.
class VSphereTree {
 public:
  VSphereTree() = default;

  /// Builds the trees of every shape of `edges` for the Hough origin `o` (world). The tree
  /// references the set's edges: the set must outlive it.
  static VSphereTree build(const EdgeSet& edges, const Vec3& o);

  const Vec3& origin() const { return origin_; }
  const std::vector<VSphereNode>& nodes() const { return nodes_; }
  const VSphereNode& node(int i) const { return nodes_[size_t(i)]; }
  const std::vector<VSphereRoot>& roots() const { return roots_; }
  /// Edges in leaf order (pointers into the edge set's edges).
  const std::vector<const Edge*>& edges() const { return edges_; }
  /// Number of edges in plain (o-silhouette) trees and in 6D trees.
  int plain_edges() const { return plain_edges_; }
  int hough_edges() const { return int(edges_.size()) - plain_edges_; }

  /// Rejection test of node i for the shading point p: plain nodes always accept; 6D nodes
  /// (leaves included: the box of their one edge's two Hough points) run the v-sphere test of
  /// `test`.
  bool may_have_silhouette(int i, const Vec3& p, VSphereTest test) const;

  /// Bytes of the arrays.
  size_t memory_bytes() const;

 private:
  Vec3 origin_ = Vec3::Zero();
  std::vector<VSphereNode> nodes_;
  std::vector<VSphereRoot> roots_;
  std::vector<const Edge*> edges_;
  int plain_edges_ = 0;
};

}  // namespace qsil::edgetree
