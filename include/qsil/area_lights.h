#pragma once
/// @file area_lights.h
/// Sampling of the area emitters of a scene: every triangle of every shape with
/// Shape::is_emitter, uniformly by area over their union (pbrt-v4 §12.2 "Area Lights" with a
/// light-power-free, area-proportional choice; Mitsuba 3 `area` emitter semantics).
///
/// Emission is one-sided (Mitsuba 3): a shape emits its constant `radiance` only toward the side
/// of its geometric normal (counter-clockwise winding, docs/architecture.md §3), and is black from behind.
///
/// Differentiation (docs/architecture.md §4): next-event estimation keeps only the *direction* to a sampled
/// point and re-evaluates the emitter along it from the differentiable origin; the sample point,
/// its pdf and to_solid_angle() are therefore double and detached.

#include "qsil/math.h"
#include "qsil/sampling.h"
#include "qsil/scene.h"

#include <vector>

namespace qsil {

/// The area emitters of one scene, as a snapshot of their world-space triangles (the scene may
/// be destroyed afterwards). Immutable and thread-safe after construction.
class AreaLights {
 public:
  /// Collects the triangles of all shapes with is_emitter (zero-area triangles get probability 0).
  explicit AreaLights(const Scene& scene);

  /// True when the scene has no emitting triangle of positive area.
  bool empty() const { return total_area_ <= 0; }

  /// A point on an emitter: world position, unit geometric normal (the emitting side), the
  /// scene's shape index and the triangle index within that shape's mesh, and the density per
  /// unit area (1 / total emitting area). pdf_area = 0 marks an invalid sample (empty()).
  struct Sample {
    Vec3 point = Vec3::Zero();
    Vec3 normal = Vec3::Zero();
    int shape = -1;
    int triangle = -1;
    double pdf_area = 0;
  };

  /// Uniform by area over all emitting triangles: u_triangle in [0,1) picks a triangle with
  /// probability area/total (never a zero-area one), u in [0,1)^2 a uniform point in it.
  Sample sample(const Vec2& u, double u_triangle) const;

  /// Density per unit area of sample() at any emitter point: 1 / total area (0 if empty()).
  double pdf_area() const { return empty() ? 0.0 : 1.0 / total_area_; }

  /// Total emitting area, scene units^2.
  double total_area() const { return total_area_; }

  /// Converts a density per unit area at `point` on an emitter with unit normal `light_normal`
  /// to a density per unit solid angle as seen from `from`:
  ///   pdf_omega = pdf_area * |point - from|^2 / |cos theta_light|,
  ///   cos theta_light = light_normal . (from - point) / |from - point|  (pbrt-v4 Eq. 4.9).
  /// Returns 0 (an invalid sample) when the point is seen exactly edge-on or coincides with `from`.
  static double to_solid_angle(double pdf_area, const Vec3& from, const Vec3& point, const Vec3& light_normal);

  /// Radiance emitted by shape `shape` (scene index) toward `dir_to_viewer` (unit, from the
  /// emitter point toward the viewer) at a point with unit geometric normal `light_normal`:
  /// the shape's radiance when light_normal . dir_to_viewer > 0, else 0 (one-sided, Mitsuba 3).
  /// 0 for a shape that is not an emitter.
  Color radiance(int shape, const Vec3& light_normal, const Vec3& dir_to_viewer) const;

 private:
  struct Triangle {
    Vec3 p0, p1, p2;
    Vec3 normal;  ///< unit geometric normal (zero for a degenerate triangle)
    int shape;
    int index;  ///< triangle index in the shape's mesh
  };
  std::vector<Triangle> triangles_;
  std::vector<Color> shape_radiance_;  ///< per scene shape: radiance if emitter, else 0
  Distribution1D by_area_;
  double total_area_ = 0;
};

}  // namespace qsil
