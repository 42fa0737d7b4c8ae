/// @file wireframe.cpp
/// See qsil/wireframe.h.

#include "qsil/wireframe.h"

#include "qsil/image.h"

#include <algorithm>
#include <cmath>

namespace qsil {

WireframeCanvas::WireframeCanvas(const Camera& camera, const Rgb& background) : cam_(camera) {
  rgb_.resize(size_t(camera.width) * camera.height * 3);
  for (size_t i = 0; i < rgb_.size(); i += 3)
    for (int c = 0; c < 3; ++c) rgb_[i + size_t(c)] = background[size_t(c)];
}

bool WireframeCanvas::project(const Vec3& p, Vec2& film) const {
  double depth = 0;
  film = cam_.project(p, &depth);
  if (!(depth > 0)) return false;
  return std::isfinite(film.x()) && std::isfinite(film.y());
}

void WireframeCanvas::plot(int x, int y, const Rgb& c, int thickness) {
  const int r0 = -(thickness - 1) / 2, r1 = thickness / 2;
  for (int dy = r0; dy <= r1; ++dy)
    for (int dx = r0; dx <= r1; ++dx) {
      const int X = x + dx, Y = y + dy;
      if (X < 0 || Y < 0 || X >= cam_.width || Y >= cam_.height) continue;
      const size_t i = (size_t(Y) * cam_.width + X) * 3;
      for (int k = 0; k < 3; ++k) rgb_[i + size_t(k)] = c[size_t(k)];
    }
}

void WireframeCanvas::line(const Vec3& a, const Vec3& b, const Rgb& color, int thickness) {
  // ---- Clip against the near plane (camera z = near_clip).
  const Vec3 la = cam_.to_camera(a), lb = cam_.to_camera(b);
  const double zn = cam_.near_clip;
  if (la.z() < zn && lb.z() < zn) return;
  Vec3 A = a, B = b;
  if (la.z() < zn) A = a + (b - a) * ((zn - la.z()) / (lb.z() - la.z()));
  if (lb.z() < zn) B = b + (a - b) * ((zn - lb.z()) / (la.z() - lb.z()));
  Vec2 fa, fb;
  if (!project(A, fa) || !project(B, fb)) return;
  // ---- Clip the 2D segment to a generous box around the film (far-off endpoints).
  const double lim = 4.0 * std::max(cam_.width, cam_.height);
  if ((fa.cwiseAbs().array() > lim).any() || (fb.cwiseAbs().array() > lim).any()) {
    double t0 = 0, t1 = 1;
    const Vec2 d = fb - fa;
    for (int k = 0; k < 2; ++k) {
      for (double bound : {-lim, lim}) {
        const double s = bound < 0 ? 1.0 : -1.0;  // inside: s (x - bound) >= 0
        const double f0 = s * (fa[k] - bound), df = s * d[k];
        if (df == 0) {
          if (f0 < 0) return;
          continue;
        }
        const double t = -f0 / df;
        if (df > 0)
          t0 = std::max(t0, t);
        else
          t1 = std::min(t1, t);
      }
    }
    if (t0 > t1) return;
    const Vec2 na = fa + t0 * d, nb = fa + t1 * d;
    fa = na;
    fb = nb;
  }
  // ---- DDA.
  const Vec2 d = fb - fa;
  const int steps = std::max(1, int(std::ceil(std::max(std::abs(d.x()), std::abs(d.y())))));
  for (int i = 0; i <= steps; ++i) {
    const Vec2 q = fa + d * (double(i) / steps);
    plot(int(std::floor(q.x())), int(std::floor(q.y())), color, thickness);
  }
}

void WireframeCanvas::dot(const Vec3& p, const Rgb& color, int radius) {
  Vec2 f;
  if (!project(p, f)) return;
  const int cx = int(std::floor(f.x())), cy = int(std::floor(f.y()));
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx)
      if (dx * dx + dy * dy <= radius * radius) plot(cx + dx, cy + dy, color, 1);
}

void WireframeCanvas::write(const std::filesystem::path& path) const { write_png(path, cam_.width, cam_.height, rgb_); }

Camera overview_camera(const Scene& scene) {
  Camera c = scene.camera;
  const Box3 b = scene.bounds();
  const Vec3 centre = b.center();
  const double radius = 0.5 * b.diagonal();
  const Vec3 up = scene.camera.to_world.block<3, 1>(0, 1).normalized();
  Vec3 side = scene.camera.origin() - centre;
  side -= side.dot(up) * up;
  if (!(side.norm() > 0)) side = -scene.camera.to_world.block<3, 1>(0, 2);
  side.normalize();
  const Vec3 dir_to_eye = (std::cos(kPi / 6) * side + std::sin(kPi / 6) * up).normalized();
  const Vec2 th = scene.camera.tan_half_fov();
  const double tmin = std::min(th.x(), th.y());
  const double dist = radius / std::sin(std::atan(tmin)) * 1.05;
  const Vec3 eye = centre + dist * dir_to_eye;
  // dir_to_eye is 30 degrees off the plane perpendicular to `up`, so up is never parallel to it.
  c.to_world = look_at(eye, centre, up);
  return c;
}

}  // namespace qsil
