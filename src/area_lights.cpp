/// @file area_lights.cpp
/// Area-emitter sampling (see include/qsil/area_lights.h).

#include "qsil/area_lights.h"

#include <cmath>

namespace qsil {

AreaLights::AreaLights(const Scene& scene) {
  shape_radiance_.assign(scene.shapes.size(), Color::Zero());
  std::vector<double> areas;
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const Shape& shape = scene.shapes[s];
    if (!shape.is_emitter) continue;
    shape_radiance_[s] = shape.radiance;
    const TriangleMesh& mesh = shape.mesh;
    for (int f = 0; f < mesh.num_triangles(); ++f) {
      const auto& t = mesh.triangles[size_t(f)];
      Triangle tri{mesh.positions[size_t(t[0])],
                   mesh.positions[size_t(t[1])],
                   mesh.positions[size_t(t[2])],
                   Vec3::Zero(),
                   int(s),
                   f};
      const Vec3 cross = (tri.p1 - tri.p0).cross(tri.p2 - tri.p0);
      const double len = cross.norm();
      if (len > 0 && std::isfinite(len)) tri.normal = cross / len;
      triangles_.push_back(tri);
      areas.push_back(tri.normal.isZero() ? 0.0 : 0.5 * len);
    }
  }
  if (!areas.empty()) {
    by_area_ = Distribution1D(areas);
    // Summed once, in the same order as the distribution, so pdf_area() * total = 1 exactly
    // up to one rounding.
    total_area_ = by_area_.integral() * double(areas.size());
  }
}

AreaLights::Sample AreaLights::sample(const Vec2& u, double u_triangle) const {
  Sample s;
  if (empty()) return s;
  const Distribution1D::Sample pick = by_area_.sample_discrete(u_triangle);
  const Triangle& t = triangles_[size_t(pick.index)];
  const Vec3 b = square_to_uniform_triangle(u);
  s.point = b[0] * t.p0 + b[1] * t.p1 + b[2] * t.p2;
  s.normal = t.normal;
  s.shape = t.shape;
  s.triangle = t.index;
  s.pdf_area = 1.0 / total_area_;
  return s;
}

double AreaLights::to_solid_angle(double pdf_area, const Vec3& from, const Vec3& point, const Vec3& light_normal) {
  const Vec3 d = from - point;
  const double dist2 = d.squaredNorm();
  if (!(dist2 > 0)) return 0.0;
  const double cos_light = std::abs(light_normal.dot(d)) / std::sqrt(dist2);
  if (!(cos_light > 0)) return 0.0;
  return pdf_area * dist2 / cos_light;
}

Color AreaLights::radiance(int shape, const Vec3& light_normal, const Vec3& dir_to_viewer) const {
  if (shape < 0 || size_t(shape) >= shape_radiance_.size()) return Color::Zero();
  return light_normal.dot(dir_to_viewer) > 0 ? shape_radiance_[size_t(shape)] : Color::Zero();
}

}  // namespace qsil
