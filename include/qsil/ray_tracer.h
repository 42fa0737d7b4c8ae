#pragma once
/// @file ray_tracer.h
/// Ray queries against a scene's triangle meshes through Embree 3 (src/ray_tracer.cpp is the only
/// file that includes Embree). One RTCScene per RayTracer, one geometry per shape (geometry id =
/// shape index), robust mode. Geometry is uploaded in float; callers that need exact hit points
/// recompute them in double from the hit's triangle (docs/architecture.md §4: Embree only chooses the triangle).

#include "qsil/math.h"
#include "qsil/scene.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <type_traits>
#include <vector>

namespace qsil {

/// A ray hit: which triangle, and Embree's (float-accurate) distance and barycentrics.
struct Hit {
  int shape = -1;       ///< shape index, -1 for a miss
  int triangle = -1;    ///< triangle index within the shape
  double t = kInf;      ///< distance along the (unit) ray direction, scene units
  double u = 0, v = 0;  ///< barycentrics of vertices 1 and 2
  /// u, v are exact (a point known on the triangle, e.g. a sampled edge point), so the surface
  /// point is interpolated from them instead of intersecting a ray with the triangle's plane
  /// (which degenerates when the ray grazes the plane).
  bool exact = false;
  /// For an exact point: the in-plane direction (world) into the part of the triangle whose limit
  /// the point stands for (SurfaceInteraction::inward; its length scales the offset of rays
  /// leaving it, at least 1); zero: toward the triangle's centroid (a point on its boundary).
  Vec3 inward = Vec3::Zero();
  bool valid() const { return shape >= 0; }
};

/// What a ray must not hit: up to two triangles (e.g. the two faces of a sampled edge, or the
/// triangle the ray starts on; shape = -1 marks an unused slot), and optionally the back side of
/// every one-sided surface (`through_back_faces`).
///
/// Why rays pass through back faces: a "sliver" ray (leaving a surface on the side opposite to
/// the viewer, through a shading normal tilted past the geometric one) starts inside the mesh;
/// if back faces stopped it, the radiance would jump at every edge of a smooth-shaded mesh, a
/// discontinuity on no silhouette that no edge sampler finds (docs/design-notes.md "Smooth shading").
struct IgnoreSet {
  std::array<std::pair<int, int>, 2> prims{{{-1, -1}, {-1, -1}}};
  bool through_back_faces = false;  ///< skip hits on the back side of one-sided surfaces
  bool contains(int shape, int tri) const {
    return (prims[0].first == shape && prims[0].second == tri) || (prims[1].first == shape && prims[1].second == tri);
  }
  /// True when no hit is filtered (Embree then runs without a filter function).
  bool empty() const { return prims[0].first < 0 && prims[1].first < 0 && !through_back_faces; }
};

/// Embree scene over all shapes of a Scene. Thread-safe for queries after construction.
///
/// Embree works relative to a local origin c (embree_local_origin): vertices and ray origins are
/// translated by -c in double, then converted to float, so Embree's float geometry is accurate
/// relative to the scene's own size, not to its distance from the world origin
/// (docs/architecture.md §3 "Precision").
class RayTracer {
 public:
  /// Builds the acceleration structure over `scene.shapes` (positions translated by
  /// -embree_local_origin(scene) and converted to float). Throws qsil::Error if Embree cannot be
  /// initialised.
  explicit RayTracer(const Scene& scene);
  /// The same with a given local origin (e.g. a displaced copy of a scene that must round its
  /// static geometry exactly as the original: finite differences).
  RayTracer(const Scene& scene, const Vec3& local_origin);
  /// Takes every shape's current vertex positions and triangles from `scene` (the scene built,
  /// with the same vertex and triangle counts: an optimiser's step) and rebuilds the acceleration
  /// structure over them, keeping the local origin. Returns false, changing nothing, when the
  /// number of shapes or a shape's vertex or triangle count differs (build a new tracer then).
  /// Throws qsil::Error if Embree fails. Not to be called while another thread queries.
  bool update_meshes(const Scene& scene);
  ~RayTracer();
  RayTracer(const RayTracer&) = delete;
  RayTracer& operator=(const RayTracer&) = delete;

  /// Closest hit of the ray origin + t*dir, t in [0, tmax), dir unit length (world space).
  /// A ray that is not ray_is_valid() never reaches Embree: it hits nothing and is counted
  /// (invalid_rays(), total_invalid_rays()).
  Hit intersect(const Vec3& origin, const Vec3& dir, double tmax = kInf, const IgnoreSet& ignore = {}) const;
  /// True if anything is hit for t in [0, tmax). An invalid ray (see intersect) is not occluded
  /// and is counted.
  bool occluded(const Vec3& origin, const Vec3& dir, double tmax, const IgnoreSet& ignore = {}) const;

  /// Number of invalid rays this tracer refused (treated as misses) so far. Thread-safe.
  uint64_t invalid_rays() const;
  /// Number of invalid rays refused by every RayTracer of the process so far (the CLI prints a
  /// warning when it is non-zero). Thread-safe.
  static uint64_t total_invalid_rays();

  /// The local origin that Embree's coordinates are relative to.
  const Vec3& local_origin() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Two triangles, each named by its mesh (an index into the span given to
/// overlapping_triangle_pairs) and its triangle index; (mesh0, triangle0) < (mesh1, triangle1).
struct TrianglePair {
  int mesh0 = -1, triangle0 = -1;
  int mesh1 = -1, triangle1 = -1;
  friend bool operator==(const TrianglePair&, const TrianglePair&) = default;
};

/// The broad phase of intersection curves (qsil/edgetree/intersection_curves.h): calls
/// `visit(pair)` once for every pair of distinct triangles of `meshes` (between two meshes and
/// within one) whose axis-aligned bounding boxes overlap (closed boxes, in double), from several
/// threads at once and in no particular order (Embree's rtcCollide over one box per triangle,
/// rounded outward to float, then the exact box test in double). Nothing is stored per pair (a
/// million-triangle mesh has tens of millions). Meshes with non-finite coordinates or degenerate
/// triangles are accepted (a non-finite box overlaps nothing).
/// `gap` >= 0 (scene units): the pairs whose boxes lie within `gap` of each other on every axis
/// instead (lo_a <= hi_b + gap and lo_b <= hi_a + gap, evaluated in double: rounding is monotone,
/// so every pair within `gap` in exact arithmetic is visited); 0: those that overlap.
/// `build_seconds` (optional) receives the time of Embree's BVH build. Throws qsil::Error if
/// Embree cannot be initialised.
void for_each_overlapping_triangle_pair(std::span<const TriangleMesh* const> meshes,
                                        const std::function<void(const TrianglePair&)>& visit,
                                        double* build_seconds = nullptr, double gap = 0.0);

/// for_each_overlapping_triangle_pair's pairs (with `gap`), sorted (for tests and small meshes).
std::vector<TrianglePair> overlapping_triangle_pairs(std::span<const TriangleMesh* const> meshes, double gap = 0.0);

/// The triangles near a ray: a BVH (Embree user geometry) over every triangle's axis-aligned
/// box grown by `reach` on every side, for estimators whose rays see triangles they do not hit
/// (regularised visibility, qsil/integrators/regularized_visibility.h: a triangle's blurred
/// opacity reaches `reach` beyond its edges). Boxes are taken in double, relative to the scene's
/// Embree local origin (embree_local_origin), rounded outward to float and padded by 2^-12 of the
/// largest grown coordinate, which covers the float rounding of rays whose origin lies within
/// ~1000 scene sizes of the local origin: for those the query misses no triangle whose grown box
/// the ray crosses. Thread-safe for queries after construction.
class NearTriangleQuery {
 public:
  /// Builds the BVH over `scene.shapes`. Throws qsil::Error when reach is negative or not finite,
  /// or Embree cannot be initialised.
  NearTriangleQuery(const Scene& scene, double reach);
  ~NearTriangleQuery();
  NearTriangleQuery(const NearTriangleQuery&) = delete;
  NearTriangleQuery& operator=(const NearTriangleQuery&) = delete;

  /// Calls visit(user, shape, triangle) once for every triangle whose grown box the segment
  /// origin + t dir, t in [0, tmax], crosses (dir non-zero; the box test is exact in double), in no
  /// particular order. A ray that is not ray_is_valid visits nothing.
  void for_each(const Vec3& origin, const Vec3& dir, double tmax, void (*visit)(void*, int, int), void* user) const;
  /// The same with a callable f(shape, triangle).
  template <class F>
  void for_each(const Vec3& origin, const Vec3& dir, double tmax, F&& f) const {
    for_each(origin, dir, tmax, [](void* u, int s, int t) { (*static_cast<std::remove_reference_t<F>*>(u))(s, t); },
             static_cast<void*>(&f));
  }
  double reach() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Largest magnitude Embree 3 accepts in a ray's origin and direction components (its FLT_LARGE,
/// 1.844e18): a larger one fails Embree's `ray.valid()` assertion, which aborts the process.
inline constexpr double kEmbreeLargestRayComponent = 1.844e18;

/// True iff Embree may see the ray: origin and direction finite with every component's magnitude
/// at most kEmbreeLargestRayComponent, a non-zero direction, and tmax not NaN (+inf is allowed,
/// a negative tmax is a valid empty interval). The scene loader bounds coordinates by
/// kMaxCoordinate (scene.h), far below this, so a loaded scene only produces invalid rays from
/// arithmetic gone wrong; this check makes them misses instead of an abort.
bool ray_is_valid(const Vec3& origin, const Vec3& dir, double tmax);

/// The local origin of a scene's Embree coordinates: the centre of the scene's bounding box rounded
/// to a multiple of q, the smallest power of two not below its diagonal (zero for an empty or
/// non-finite box; the centre itself for a box of zero size). Every vertex x then has
/// |x - c| <= q per coordinate; x - c is formed in double (exact when |x| >= q, as c is a
/// multiple of q) before the rounding to float. Rounding keeps c where it is under small
/// displacements, and zero for scenes whose centre is within q/2 of the origin on every axis
/// (their Embree geometry is unchanged).
Vec3 embree_local_origin(const Scene& scene);

/// Origin offset for a ray leaving a surface point p with geometric normal ng toward dir: moves p
/// along ±ng by a distance relative to the coordinate magnitude max(`scale`, |p - local_origin|)
/// (`scale`: the largest absolute vertex coordinate of the triangle relative to `local_origin`,
/// the ray tracer's RayTracer::local_origin), which bounds the float error of Embree's geometry,
/// itself relative to the local origin. No absolute epsilon (docs/architecture.md §3 "Precision"):
/// scenes span 1e-3 to 1e4 units (history: docs/experiments/2026-11-25-readme-figures.md,
/// "Coordinates far from the origin").
Vec3 offset_ray_origin(const Vec3& p, const Vec3& ng, const Vec3& dir, double scale,
                       const Vec3& local_origin = Vec3::Zero());

/// Relative size of the offset used by offset_ray_origin (times the coordinate magnitude): 2^-20,
/// 8 float ulps of the coordinates (2^-15 biased scenes far from the origin: measurements in
/// docs/experiments/2026-11-25-header-notes.md, "ray_tracer.h: kRayOffsetRelative").
inline constexpr double kRayOffsetRelative = 1.0 / 1048576.0;

}  // namespace qsil
