/// @file camera.cpp
/// The perspective camera of Mitsuba 3 and two small Scene queries. See qsil/scene.h.
///
/// Camera space looks along +z with +x to the image's left and +y up (Mitsuba's lookat builds
/// the columns [left, up, dir, origin]). A film position (fx, fy) in pixels, (0,0) the image's
/// top-left corner, maps to the camera-space direction
///     ((1 - 2 fx/W) tan_x, (1 - 2 fy/H) tan_y, 1),
/// which is Mitsuba's perspective_projection() inverted: sample x = 0.5 (1 - x/(z tan_x)).

#include "qsil/scene.h"

#include <cmath>
#include <stdexcept>
#include <string_view>

namespace qsil {

namespace {
double deg_to_rad(double d) { return d * kPi / 180.0; }
}  // namespace

Vec2 Camera::tan_half_fov() const {
  // Mitsuba 3 parse_fov(): convert the field of view along fov_axis into the horizontal one.
  const double aspect = double(width) / double(height);
  const bool wide = aspect > 1;
  const std::string_view axis = fov_axis == "smaller"  ? (wide ? "y" : "x")
                                : fov_axis == "larger" ? (wide ? "x" : "y")
                                                       : std::string_view(fov_axis);
  const double t = std::tan(0.5 * deg_to_rad(fov_deg));
  double tan_x;
  if (axis == "x") {
    tan_x = t;
  } else if (axis == "y") {
    tan_x = t * aspect;
  } else if (axis == "diagonal") {
    // tan of half the diagonal = t; the film's half-width is t / sqrt(1 + 1/aspect^2).
    tan_x = t / std::sqrt(1.0 + 1.0 / (aspect * aspect));
  } else {
    throw std::invalid_argument("Camera: unknown fov_axis '" + fov_axis + "'");
  }
  return Vec2(tan_x, tan_x / aspect);
}

Mat4 look_at(const Vec3& origin, const Vec3& target, const Vec3& up) {
  const Vec3 dir = (target - origin).normalized();
  const Vec3 left = up.cross(dir).normalized();
  Mat4 m = Mat4::Identity();
  m.block<3, 1>(0, 0) = left;
  m.block<3, 1>(0, 1) = dir.cross(left);
  m.block<3, 1>(0, 2) = dir;
  m.block<3, 1>(0, 3) = origin;
  return m;
}

Vec3 Camera::direction(double fx, double fy) const {
  const Vec2 t = tan_half_fov();
  const Vec3 local((1.0 - 2.0 * fx / width) * t.x(), (1.0 - 2.0 * fy / height) * t.y(), 1.0);
  return (to_world.block<3, 3>(0, 0) * local).normalized();
}

Vec3 Camera::to_camera(const Vec3& x) const { return to_world.block<3, 3>(0, 0).transpose() * (x - origin()); }

Vec2 Camera::project(const Vec3& x, double* depth) const {
  const Vec3 c = to_camera(x);
  const Vec2 t = tan_half_fov();
  if (depth) *depth = c.z();
  return Vec2(0.5 * width * (1.0 - c.x() / (c.z() * t.x())), 0.5 * height * (1.0 - c.y() / (c.z() * t.y())));
}

Box3 Scene::bounds() const {
  Box3 b;
  for (const auto& s : shapes) b.expand(s.mesh.bounds());
  return b;
}

int Scene::find_shape(const std::string& id) const {
  for (int i = 0; i < int(shapes.size()); ++i)
    if (shapes[i].id == id) return i;
  return -1;
}

}  // namespace qsil
