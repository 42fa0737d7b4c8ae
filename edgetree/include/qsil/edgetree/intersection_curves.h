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
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"

#include <array>
#include <cstdint>
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
  double build_seconds = 0;       ///< wall time of Embree's BVH over the triangles' boxes (0 from a cache)
  double seconds = 0;             ///< wall time of everything (the exact tests run inside rtcCollide)
  bool from_cache = false;        ///< the pairs were a CandidatePairCache's (no broad phase)
};

/// The gap of a CandidatePairCache, in the meshes' mean edge lengths: the pairs kept are those
/// whose boxes lie within it of each other, and the cache serves until some vertex has moved half
/// of it. It starts at kCandidatePairGap and adapts to how far the vertices move between searches
/// within [kCandidatePairMinGap, kCandidatePairMaxGap]; kCandidatePairRest searches run without
/// the cache where even the largest gap served none. Measured in
/// docs/experiments/2026-11-26-candidate-pair-cache.md: at a gap of 0.5 a closed mesh keeps 7.5
/// (icospheres) to 11 (Spot) pairs per triangle, a fill costs 1.3-1.5 searches without a cache
/// and a search from it about 0.4; at 1, 18-26 pairs, about 2 and 0.5-0.6, where a fill pays only
/// if it serves three searches: not worth the wait.
inline constexpr double kCandidatePairGap = 0.5;
inline constexpr double kCandidatePairMinGap = 0.125;
inline constexpr double kCandidatePairMaxGap = 0.5;
inline constexpr int kCandidatePairRest = 8;

/// The broad phase's pairs, kept for later searches over the same meshes after their vertices
/// moved a little (EdgeForest::refit: an optimiser's steps), so that those skip Embree's BVH
/// build and traversal. Filled and read by find_intersection_curves only.
///
/// Why a search from the cache finds exactly what a search without one finds: the cache holds
/// every pair of distinct triangles whose boxes (closed, in double) lay within `gap` of each other
/// on every axis at `positions`, but the pairs of one mesh that share an edge by index (those
/// never cross and always overlap: only their count is kept). A box's bounds are its vertices'
/// coordinates, so when no vertex has moved more than d on any axis since, two boxes that
/// overlap now lay within 2 d of each other then. A search reuses the cache where 2 d <= gap (d
/// bounded above despite rounding: a difference of doubles is rounded relative to itself), the
/// meshes have the same vertex and triangle counts and triangles (a hash), and every coordinate
/// is finite; it then applies the exact box test of the broad phase to the cached pairs. Else it
/// runs the broad phase with the gap, fills the cache anew and keeps the positions (or, where
/// filling has not paid, runs without it for a while: see kCandidatePairRest).
/// Memory: 8 bytes per cached pair (7.5-11 per triangle at kCandidatePairGap on closed meshes,
/// about 21 on the teapot's) and 24 per vertex. Not thread-safe: one search at a time per cache.
struct CandidatePairCache {
  /// A pair by the triangles' indices over all meshes in turn (mesh m's triangle f is
  /// first_triangle[m] + f): half a TrianglePair's size.
  struct Pair {
    int a = 0, b = 0;
  };
  std::vector<std::vector<Vec3>> positions;  ///< per mesh, as when the pairs were found
  std::vector<int> triangle_counts;          ///< per mesh
  std::vector<int> first_triangle;           ///< per mesh and one more: prefix sums of triangle_counts
  std::uint64_t triangles_hash = 0;          ///< of every mesh's triangles, in order
  double gap = 0.0;                          ///< scene units (kCandidatePairGap x mean edge length)
  std::vector<Pair> pairs;                   ///< in the broad phase's order (its threads' in turn)
  long long edge_sharing_pairs = 0;          ///< pairs of one mesh sharing an edge by index (not in `pairs`)
  bool valid = false;                        ///< filled by a search (false: empty)
  double gap_edges = kCandidatePairGap;      ///< the gap of the next fill, in mean edge lengths
  int served = 0;                            ///< searches served since the fill
  int rest = 0;                              ///< searches left to run without the cache
  /// Bytes of its arrays.
  size_t memory_bytes() const;
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
/// receives the counts and times. `cache` (optional): where it holds for `meshes` (see
/// CandidatePairCache) the pairs come from it instead of the broad phase, else the broad phase
/// fills it; the result and the counts are the same either way, bit for bit (where every
/// coordinate is finite, as the scene loader and set_vertices require).
std::vector<CrossingSegment> find_intersection_curves(std::span<const CurveMesh> meshes,
                                                      IntersectionCurveStats* stats = nullptr,
                                                      CandidatePairCache* cache = nullptr);

}  // namespace qsil::edgetree
