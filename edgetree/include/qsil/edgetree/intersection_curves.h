#pragma once
/// @file intersection_curves.h
/// Intersection curves: where two surfaces cross (two shapes, or two parts of one shape), the
/// curve where they meet bounds what each one sees of the other ([QSS] §2, "implicit edges caused
/// by self-intersections"; Zhang et al. 2019 call them implicit edges). No edge of either mesh lies
/// on it, yet it is a discontinuity of the radiance seen from any point, and it moves when either
/// surface moves (docs/architecture.md §5 "Intersection curves").
///
/// A curve is found as segments, one per pair of crossing triangles A and B: the part of the line
/// where their planes meet that lies in both. Each end of a segment is where an edge (a, b) of one
/// of the two triangles crosses the plane of the other (c0, c1, c2), or, for two triangles that
/// share a vertex, that vertex; as the vertices move, the end moves with them, so its velocity is
/// a linear function of the five vertices' velocities (CrossingEnd::jacobian), and so is that of
/// every point between the ends (their interpolation: the normal component, the only one the
/// boundary term reads, is exact).
///
/// Frames and units: world frame, scene units.

#include "qsil/math.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

#include <array>
#include <span>
#include <vector>

namespace qsil::edgetree {

/// A vertex of a scene: its shape and its index in the shape's mesh (shape -1: unused).
struct VertexRef {
  int shape = -1;
  int vertex = -1;
};

/// One end of a crossing segment (see the file comment): the point where edge (a, b) of one
/// triangle crosses the plane of triangle (c0, c1, c2), or a vertex shared by the two triangles.
struct CrossingEnd {
  /// a, b, c0, c1, c2 in that order; for a shared vertex, vertices[0] only (the others unused).
  std::array<VertexRef, 5> vertices;
  /// d(end)/d(position of vertices[i]) in columns [3i, 3i + 3) (world, dimensionless); zero
  /// columns for unused vertices. First order: the end's velocity is sum_i J_i dx_i/dtheta.
  Eigen::Matrix<double, 3, 15> jacobian = Eigen::Matrix<double, 3, 15>::Zero();
};

/// A segment of an intersection curve between triangle `face[0]` of shape `shape[0]` (A) and
/// triangle `face[1]` of shape `shape[1]` (B): both triangles cross each other's plane along it.
struct CrossingSegment {
  std::array<int, 2> shape{-1, -1};  ///< shapes of A and B (the same shape for a self-intersection)
  std::array<int, 2> face{-1, -1};   ///< triangles of A and B in their shapes' meshes
  /// Planes of A and B, [n, -n.x0] with unit outward n (docs/architecture.md §3).
  std::array<Vec4, 2> plane{Vec4::Zero(), Vec4::Zero()};
  Vec3 p0 = Vec3::Zero(), p1 = Vec3::Zero();  ///< its ends (world, scene units), p0 != p1
  std::array<CrossingEnd, 2> ends;            ///< how p0 and p1 move
};

/// The velocity of a crossing end for every parameter: sum_i J_i dx_i/dtheta (3 x
/// kMaxParameters, world units per unit theta; columns >= velocities.num_params are zero).
SceneVelocities::Block crossing_end_velocity(const CrossingEnd& end, const SceneVelocities& velocities);

/// One mesh given to find_intersection_curves: the mesh and the shape index its segments name.
struct CurveMesh {
  const TriangleMesh* mesh = nullptr;
  int shape = 0;
};

/// What find_intersection_curves did (for set-up reports, `qsil forest --stats` and the benchmark).
struct IntersectionCurveStats {
  long long candidate_pairs = 0;  ///< triangle pairs whose boxes overlap (the broad phase)
  long long crossing_pairs = 0;   ///< of which cross each other (a segment each)
  double build_seconds = 0;       ///< wall time of Embree's BVH over the triangles' boxes
  double seconds = 0;             ///< wall time of everything (the exact tests run inside rtcCollide)
};

/// Every crossing segment between the triangles of `meshes`, between two meshes and within one
/// (self-intersections), in a deterministic order (by the pair's mesh and triangle indices).
///
/// Broad phase: for_each_overlapping_triangle_pair (Embree's rtcCollide); the narrow phase runs
/// in its callback, on Embree's threads, so no pair is stored. Narrow phase, per pair: the
/// side of each vertex of one triangle against the other's plane is the exact orientation
/// predicate (CGAL's Exact_predicates_inexact_constructions_kernel), so whether two triangles
/// cross is decided exactly; the segment's ends are then constructed in double from the edges and
/// planes that the predicates chose. Rules, which make touching without crossing give nothing:
/// - triangles sharing two or more vertex positions (an edge, or one triangle twice) do not cross;
/// - each triangle must have a vertex strictly on each side of the other's plane, so coplanar
///   triangles, and a surface resting on another at a vertex, an edge or a face, cross nothing
///   (the resting surface's own edges bound what is seen there);
/// - except along an edge that lies exactly in the other plane, with the edge's two triangles
///   strictly on opposite sides of it: the surface passes through the other there (a ring of
///   vertices exactly in a floor), and the triangle whose third vertex is in front gives the
///   segment;
/// - the two triangles' intervals on the planes' common line must overlap in more than a point.
/// An end at a vertex that lies in the other plane (shared by both triangles, or exactly on it)
/// is that vertex, and moves with it (one-sided: where it leaves the plane, the end follows one
/// of its edges). Throws qsil::Error if Embree cannot be initialised. `stats` (optional)
/// receives the counts and times.
std::vector<CrossingSegment> find_intersection_curves(std::span<const CurveMesh> meshes,
                                                      IntersectionCurveStats* stats = nullptr);

}  // namespace qsil::edgetree
