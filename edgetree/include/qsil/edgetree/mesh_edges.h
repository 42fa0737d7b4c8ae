#pragma once
/// @file mesh_edges.h
/// Undirected edges of a welded triangle mesh with their two faces, classified as convex,
/// concave, flat, boundary or non-manifold (docs/architecture.md §5 "Edges", [QSS 4.1]).
///
/// Frames and units: everything is in the mesh's own (world) frame, scene units; angles in
/// radians. A face plane is the homogeneous 4-vector q = [n, -n.x0] with unit outward normal n
/// (counter-clockwise winding is outward, docs/architecture.md §3); for a point x = [p, 1], q.x > 0 means p
/// is in front of the face.

#include "qsil/math.h"
#include "qsil/scene.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace qsil::edgetree {

/// Class of an undirected mesh edge.
/// - Convex: two consistently oriented faces, interior dihedral angle < pi.
/// - Concave: interior dihedral angle > pi; never a silhouette of a closed opaque mesh seen from
///   outside [QSS 4.1, Table 2]; culled unless EdgeOptions::keep_concave.
/// - Flat: the exterior bend angle (angle between the two outward normals) is below
///   kFlatAngle = 1e-4 rad (the criterion of tests/data/meshes/README.md); culled.
/// - Boundary: exactly one adjacent face; a discontinuity for every shading point.
/// - NonManifold: more than two adjacent faces; reported and treated as boundary.
/// - Inconsistent: two faces that traverse the edge in the same direction (inconsistent winding);
///   counted and treated as boundary (always a candidate), which is conservative.
/// - Intersection: no mesh edge but a segment of an intersection curve, where triangle f0 of one
///   shape crosses triangle f1 of another (or of the same) shape (intersection_curves.h); a
///   discontinuity for every shading point. Never made by build_mesh_edges.
enum class EdgeClass : std::uint8_t { Convex, Concave, Flat, Boundary, NonManifold, Inconsistent, Intersection };

/// Number of EdgeClass values (the size of per-class counters).
inline constexpr int kEdgeClassCount = 7;

/// Exterior bend angle (radians) below which an interior edge is flat (meshes README criterion).
inline constexpr double kFlatAngle = 1e-4;

/// One undirected mesh edge (or, with cls Intersection, a segment of an intersection curve: v0 =
/// v1 = -1, f0 and f1 the crossing triangles of two shapes, q0 and q1 their planes, `shape` the
/// index of its crossing group; see Edge::crossing).
struct MeshEdge {
  int v0 = -1, v1 = -1;    ///< vertex indices into TriangleMesh::positions, v0 < v1
  int f0 = -1, f1 = -1;    ///< adjacent faces (indices into TriangleMesh::triangles);
                           ///< f1 = -1 for boundary edges; for non-manifold edges the first two
  Vec4 q0 = Vec4::Zero();  ///< plane of f0, [n, -n.x0], unit n (world frame)
  Vec4 q1 = Vec4::Zero();  ///< plane of f1 (zero vector when f1 = -1)
  double length = 0.0;     ///< |x(v1) - x(v0)|, scene units
  double angle = 0.0;      ///< exterior dihedral (bend) angle between n0 and n1 in [0, pi],
                           ///< radians; 0 for boundary/non-manifold edges
  EdgeClass cls = EdgeClass::Convex;
  int shape = 0;  ///< index of the shape this edge belongs to
};

/// Options of edge extraction.
struct EdgeOptions {
  /// Keep concave edges as candidates. Culling them assumes a closed opaque mesh seen from
  /// outside (a camera inside a closed room sees its concave edges as silhouettes).
  bool keep_concave = false;
};

/// Edges of one mesh and their classification counts.
struct MeshEdgeSet {
  std::vector<Vec4> face_planes;  ///< one plane per triangle, [n, -n.x0], unit n (zero if degenerate)
  std::vector<MeshEdge> edges;    ///< every undirected edge, sorted by (v0, v1)
  std::vector<int> kept;          ///< indices into `edges` of the tree candidates (convex, and
                                  ///< concave when keep_concave), in `edges` order
  std::vector<int> always;        ///< indices into `edges` of the always-candidate edges
                                  ///< (boundary, non-manifold, inconsistent)
  std::array<int, kEdgeClassCount> counts{};  ///< number of edges per EdgeClass (indexed by the enum value)
  int count(EdgeClass c) const { return counts[static_cast<int>(c)]; }
};

/// Plane [n, -n.x0] of triangle f of `mesh` with unit outward n (world frame). Returns the zero
/// vector for a zero-area triangle.
Vec4 face_plane(const TriangleMesh& mesh, int f);

/// Builds the undirected edge list of a welded mesh with adjacency, planes, lengths, exterior
/// dihedral angles and classes (docs/architecture.md §5 "Edges"). `shape` is stored in every edge.
/// Cost O(T log T). The input mesh is not modified.
MeshEdgeSet build_mesh_edges(const TriangleMesh& mesh, int shape = 0, const EdgeOptions& options = {});

/// The class of an interior, consistently oriented edge e of `mesh` (faces f0 and f1 and their
/// planes q0 and q1 set, from the same positions), writing its bend angle (radians) into
/// e.angle: Flat below kFlatAngle, else Concave or Convex (see EdgeClass). What
/// build_mesh_edges does for such an edge, and what a refit (EdgeForest::refit) redoes when the
/// vertices move.
EdgeClass classify_interior_edge(const TriangleMesh& mesh, MeshEdge& e);

/// The index (into mesh.positions) of the vertex of face `face` (one of edge e's faces, an index
/// into mesh.triangles) that is not on the edge.
inline int opposite_vertex_index(const TriangleMesh& mesh, const MeshEdge& e, int face) {
  const auto& tri = mesh.triangles[size_t(face)];
  int opp = tri[0];
  for (int k = 0; k < 3; ++k)
    if (tri[k] != e.v0 && tri[k] != e.v1) opp = tri[k];
  return opp;
}

/// Exact silhouette predicate of one edge for the shading point p (world frame) [QSS 3.1]:
/// true iff (q0.x)(q1.x) <= 0 with x = [p, 1]; always true for boundary, non-manifold and
/// inconsistent edges and for intersection-curve segments. This is the ground truth of every soundness test (docs/architecture.md §3).
/// Inline: the traversal's flat choices test tens of edges per query with it.
inline bool edge_is_silhouette(const MeshEdge& e, const Vec3& p) {
  if (e.f1 < 0 || e.cls == EdgeClass::Boundary || e.cls == EdgeClass::NonManifold || e.cls == EdgeClass::Inconsistent ||
      e.cls == EdgeClass::Intersection)
    return true;
  const double g0 = e.q0.head<3>().dot(p) + e.q0[3];
  const double g1 = e.q1.head<3>().dot(p) + e.q1[3];
  return g0 * g1 <= 0.0 || !(std::isfinite(g0) && std::isfinite(g1));
}

}  // namespace qsil::edgetree
