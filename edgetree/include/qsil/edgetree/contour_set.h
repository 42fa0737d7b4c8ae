#pragma once
/// @file contour_set.h
/// The contour set of a narrow BSDF lobe or of a small light (docs/architecture.md §5
/// "Contour sets"): the silhouette edges of the surface that a ray along the lobe's axis (or
/// toward the light) meets, found by walking over that mesh, within the lobe's (the light's) core.
///
/// Why: at a glossy vertex (the GGX alpha 0.01 mirror of scenes/spot-mirror.xml) the boundary
/// integral is carried by a few visible silhouette edges where the lobe crosses the outline of
/// what it sees, which the traversal's importance (the LTC integral over a box, or over an edge)
/// cannot tell from the hidden ones just behind the surface the lobe's axis meets. The visible
/// outline is found from the mesh instead: it bounds the connected region of faces, facing p as
/// the face the axis meets does, around that face. Measured:
/// docs/experiments/2026-11-25-edge-choice.md §5 "Contour sets ...", "Light cores".
///
/// Construction (for shading point p, the lobe's core (ContourProbe) and the first hits of the
/// probe rays on faces of eligible shapes):
/// 1. Walks: from each hit, in each of kContourWalks planes through p containing its ray,
///    outward in both directions across the mesh faces the plane cuts, until the face beyond
///    the crossed edge faces p otherwise than the one before (the crossed edge is a silhouette:
///    a seed), the edge has no second face (a seed), the crossing leaves the core, or
///    kContourWalkSteps faces were crossed.
/// 2. Contour following: from the seeds over edges that share a vertex and are silhouettes too,
///    keeping the silhouette edges of the tree or always-candidate arrays (edge_is_silhouette)
///    whose arc from p enters the core, at most kMaxContourEdges of them (visiting at most
///    kMaxContourVisits), except concave ones: on a closed, opaque, consistently wound mesh seen
///    from outside, where the faces of a valley face p differently, the one facing away is
///    behind the other, so such an edge is a silhouette of no visible outline (why [QSS 4.1]
///    culls them; on a smooth mesh they are creases, always candidates of the traversal). On an
///    open or inside-out mesh this leaves visible outlines to the traversal (variance, not bias).
///    The following still passes through them: a contour on a triangle mesh may turn there.
/// The set is a deterministic function of p, the core and the hits; it holds only edges that
/// are discontinuities for p.
///
/// Light contour sets (docs/design-notes.md "Narrow self-shadow penumbrae"): where the lobe gives
/// no core (a diffuse vertex, or a lobe wider than kContourMaxHalfAngle), the core is the cone
/// from p that bounds a small light instead (light_core.h: the light, quad or light sphere, facing p
/// with the largest radiance × solid angle, a circular cone of half-angle at most
/// kContourMaxHalfAngle), and the probe rays go toward the light: in a penumbra the boundary
/// integral is carried by the outline of the occluder in front of it, which may be millimetres
/// from p, and the walks find it the same way.
///
/// Unbiasedness does not depend on how well the set is chosen: the boundary term is the sum over
/// the set (estimated by a choice among its edges, each with positive probability) plus the sum
/// over every other edge (the traversal, whose samples of edges in the set are dropped); see
/// sample_silhouette_set.

#include "qsil/edgetree/edge_choice_scratch.h"
#include "qsil/edgetree/edge_set.h"
#include "qsil/edgetree/mesh_edges.h"
#include "qsil/math.h"

#include <array>
#include <span>
#include <vector>

namespace qsil::edgetree {

/// Walk planes through each hit's ray (each walked in both directions: 2 × this many walks).
inline constexpr int kContourWalks = 4;
/// Faces a walk may cross before it stops without a seed.
inline constexpr int kContourWalkSteps = 64;
/// Largest contour set (the following stops there; the set stays a deterministic function of
/// the query, so the estimate stays unbiased).
inline constexpr int kMaxContourEdges = 64;
/// Most edges a contour following visits (kept or not: concave, culled, outside the core), so
/// that its cost per query is bounded on any mesh.
inline constexpr int kMaxContourVisits = 512;

/// Share of the BSDF lobe's LTC mass inside its core (ContourProbe), where the contour set lives:
/// a larger core finds more of the outline for more time. Value measured on spot-mirror
/// (docs/experiments/2026-11-25-header-notes.md, "contour_set.h: kContourConeMass").
inline constexpr double kContourConeMass = 0.95;
/// Lobes (and lights, seen from p) whose core cone is wider than this half-angle (radians) get no
/// contour set: their visible outline is too long for one set of at most kMaxContourEdges edges to
/// matter.
inline constexpr double kContourMaxHalfAngle = 0.3;

/// Rays a probe may trace: the cone's axis, and where that does not meet an eligible shape, a
/// ring of kContourRingRays directions at kContourRingAngle × the cone's half-angle around it.
inline constexpr int kContourRingRays = 6;
inline constexpr double kContourRingAngle = 0.5;
/// Most probe hits: the axis's, or the ring's.
inline constexpr int kMaxContourHits = kContourRingRays;
static_assert(kContourRingRays == 6, "the tables below hold 6 directions");
/// cos and sin of the ring's angles 2 pi k / kContourRingRays.
inline constexpr double kContourRingCos[6] = {1.0, 0.5, -0.5, -1.0, -0.5, 0.5};
inline constexpr double kContourRingSin[6] = {0.0, 0.86602540378443865,  0.86602540378443865,
                                              0.0, -0.86602540378443865, -0.86602540378443865};

/// A probe ray's first hit: where a contour walk starts.
struct ContourHit {
  int shape = -1;             ///< shape of the hit face
  int triangle = -1;          ///< hit face (index into the shape's triangles)
  Vec3 point = Vec3::Zero();  ///< hit point (world frame)
  Vec3 dir = Vec3::UnitZ();   ///< the probe ray's unit direction (world frame)
};

/// The probe of a query: the core of its BSDF lobe and the first hits of the probe rays from p
/// on eligible shapes. count 0: no contour set.
/// The core is the image of the cosine-domain cone that holds kContourConeMass of the LTC: the
/// directions w (world, relative to p) with (T w).z >= cos_core |T w|, T = the LTC's M_inv times
/// the world-to-local rotation (an elliptical cone that follows a stretched grazing lobe); the
/// circular cone (axis, cos_half_angle) bounds it (ltc_core_cone) and aims the probe rays.
struct ContourProbe {
  Vec3 axis = Vec3::UnitZ();          ///< unit, world frame
  double cos_half_angle = 1;          ///< the bounding cone is {w unit : w . axis >= cos_half_angle}
  Mat3 to_cosine = Mat3::Identity();  ///< T: world directions to the LTC's cosine domain
  double cos_core = 1;                ///< cos of the cosine-domain cone's half-angle
  std::array<ContourHit, kMaxContourHits> hits{};  ///< the hits on eligible shapes, hits[0 .. count)
  int count = 0;                                   ///< number of hits (0: no contour set)
  /// Whether the arc of directions from p to the segment [x0, x1] enters the core.
  bool arc_in_core(const Vec3& x0, const Vec3& x1, const Vec3& p) const;
  /// Whether the direction of x - p is in the core.
  bool in_core(const Vec3& x, const Vec3& p) const {
    const Vec3 c = to_cosine * (x - p);
    return c.z() >= cos_core * c.norm();
  }
};

/// Largest cosine, over the great arc from p to the edge's points (the directions of x0 + t (x1 -
/// x0) - p, t in [0, 1]), of the angle to the unit direction `axis`: the arc comes within the
/// cone {w : w . axis >= c} iff this is >= c. p on the edge's line: the larger of the endpoints'.
double arc_max_cos(const Vec3& x0, const Vec3& x1, const Vec3& p, const Vec3& axis);

/// Mesh adjacency of every shape of an edge set, for contour sets (see the file comment).
class ContourIndex {
 public:
  ContourIndex() = default;
  /// Builds the adjacency of every input shape's mesh (faces, edges, vertices) and links its
  /// edges to their entries in `set` (tree edges and always-candidates). O(T log T) per mesh.
  /// The meshes and `set` must outlive the index.
  static ContourIndex build(std::span<const ForestShapeInput> shapes, const EdgeSet& set);

  /// Brings the index up to date after the meshes' vertices moved and `set` was refitted
  /// (EdgeForest::refit, which moves its edges): the edges' planes and classes, the bounding
  /// spheres, and the links to `set`'s edges. O(T). Returns false, changing nothing, when a
  /// shape's mesh is not the one indexed or its vertex or face count changed (build anew then);
  /// the triangles themselves are the refit's to check.
  bool refit(std::span<const ForestShapeInput> shapes, const EdgeSet& set);

  /// The contour set for shading point p and `probe` (see the file comment): the union over the
  /// probe's hits on eligible, indexed shapes (`eligible` as SilhouetteQuery::eligible: null
  /// means every shape) of the walks from each hit (in planes through its ray) and the contour
  /// following from all their seeds, each edge once, in the order found (deterministic: walks in
  /// hit and direction order, then a depth-first following) into `out` (cleared first).
  /// `scratch`: this thread's buffers (edge_choice_scratch.h); null: the call makes its own.
  void contour_edges(const ContourProbe& probe, const Vec3& p, const std::vector<bool>* eligible,
                     std::vector<const Edge*>& out, EdgeChoiceScratch* scratch = nullptr) const;

  /// Whether the cone {w : w . axis >= cos_half_angle} from p (axis unit) meets the bounding
  /// sphere of an eligible indexed shape (`eligible` as in contour_edges): where it meets none, no
  /// probe ray can find a contour. Conservative (true when p lies inside a sphere).
  bool cone_meets_shapes(const Vec3& p, const Vec3& axis, double cos_half_angle,
                         const std::vector<bool>* eligible) const;

  /// Bytes of the index's arrays.
  size_t memory_bytes() const;

 private:
  struct Mesh {
    const TriangleMesh* mesh = nullptr;
    std::vector<std::array<int, 3>> face_edges;  ///< per face, its edges (indices into edges)
    /// build_mesh_edges' edges (concave ones classified, not culled), sorted by (v0, v1), v0 < v1.
    std::vector<MeshEdge> edges;
    /// Per edge, its entry in the edge set (tree edge or always-candidate); null: not in the set
    /// (flat, or culled).
    std::vector<const Edge*> entries;
    std::vector<int> vertex_begin;  ///< CSR: edges at vertex v are vertex_edges[vertex_begin[v] .. vertex_begin[v+1])
    std::vector<int> vertex_edges;
    int first_edge = 0;          ///< number of the mesh's first edge among all meshes' edges (visited sets)
    Vec3 centre = Vec3::Zero();  ///< bounding sphere of the vertices (world frame)
    double radius = 0;
  };
  /// Index of the edge (a, b) in m.edges (sorted by (v0, v1), v0 < v1), -1 if none.
  static int find_edge(const Mesh& m, int a, int b);
  /// Links every mesh edge to its entry in `set` (Mesh::entries).
  void link(const EdgeSet& set);
  std::vector<Mesh> meshes_;  ///< by shape index (empty Mesh for shapes not in the input)
  int total_edges_ = 0;       ///< edges of all meshes
};

}  // namespace qsil::edgetree
