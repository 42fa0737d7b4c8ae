#pragma once
/// @file silhouette_projection.h
/// Projection of a path segment onto a nearby silhouette (Zhang, Roussel, Jakob 2023, §5.2
/// "projected seeds"; the role of Mitsuba 3's `ProjectiveDetail.ProjectOperation` with
/// mesh_proj_algo "hybrid": a walk over the mesh, then one Newton jump): the seeds from which
/// projective sampling's octree guide learns where in the boundary sample space the integrand
/// lives (docs/architecture.md §16).
///
/// A seed is a viewpoint x (a vertex of a camera path) and the hit of a ray from x on a mesh. The
/// projection looks for an edge of the hit's mesh near the hit that is a silhouette seen from x
/// (or a crease of a flat-shaded shape); it returns the boundary segment through a point y on it
/// with direction w = (y - x) / |y - x|, whose shading point is then x again wherever nothing lies
/// between. The segment is a guess: the guide only weighs the sample space by the integrand found
/// at the projected points and keeps a uniform share, so a poor projection costs variance, never
/// bias.

#include "projective_boundary.h"

#include <array>
#include <optional>
#include <vector>

namespace qsil {

/// Per shape and triangle, the indices (into ProjectiveEdges::edges) of the triangle's mesh edges
/// in the boundary sample space: up to three, -1 for an edge the sample space leaves out (flat,
/// retired, a culled concave edge of a closed smooth mesh; a non-manifold edge is its first two
/// faces'). Intersection-curve segments are no triangle's. The walk crosses only these edges.
struct TriangleEdges {
  std::vector<std::vector<std::array<int, 3>>> of;  ///< of[shape][triangle]
  /// The edges of triangle f of shape s (all -1 for a shape or triangle out of range).
  std::array<int, 3> at(int s, int f) const {
    if (s < 0 || s >= int(of.size()) || f < 0 || f >= int(of[size_t(s)].size())) return {-1, -1, -1};
    return of[size_t(s)][size_t(f)];
  }
};

/// The triangles' edges of `scene`'s shapes in `edges`.
TriangleEdges triangle_edges(const Scene& scene, const ProjectiveEdges& edges);

/// Steps of the projection's walk across the mesh before its Newton jump (Mitsuba 3's
/// proj_mesh_max_walk has the same role).
inline constexpr int kProjectionMaxWalk = 8;

/// The projection of the seed (viewpoint x, `hit` of a ray from x on a mesh) onto a boundary
/// segment, as the point u of boundary_segment's unit cube (the file comment): the hit's triangle
/// and then up to kProjectionMaxWalk neighbours, each across the edge whose far face is seen most
/// nearly edge-on from x (never straight back), are searched for a silhouette seen from x (or a
/// crease of a flat-shaded shape); where none is found, one Newton step from a random point of the
/// last triangle moves toward where the interpolated shading normal is perpendicular to the view
/// from x (n_s . (x - p) = 0, to first order in its barycentrics) and the triangle below that
/// point is searched. The edge among those found and t on it are drawn uniformly from `sampler`.
/// None when no edge is found. Counts rays in `stats`.
std::optional<Vec3> project_seed(const PathContext& ctx, const ProjectiveEdges& edges, const TriangleEdges& tri,
                                 const Vec3& x, const Hit& hit, Sampler& sampler, PathStats& stats);

}  // namespace qsil
