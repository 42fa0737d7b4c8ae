/// @file environment_sun.cpp
/// The sun of an environment map; see qsil/environment_sun.h.

#include "qsil/environment_sun.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace qsil {

std::optional<EnvironmentSun> find_environment_sun(const EnvironmentLight& env) {
  const int W = env.width(), H = env.height();
  if (W <= 0 || H <= 0) return std::nullopt;
  // ---- Per row: the polar angle's cosine and sine at the centre, the texels' solid angle and
  // angular radius (half the diagonal: pi / H in theta, 2 pi / W times the row's largest sin theta
  // in phi); per column: phi's sine and cosine at the centre.
  const size_t rows = size_t(H), cols = size_t(W);
  std::vector<double> row_cos(rows), row_sin(rows), row_omega(rows), row_radius(rows);
  for (int y = 0; y < H; ++y) {
    const double theta0 = kPi * y / H, theta1 = kPi * (y + 1) / H, theta = kPi * (y + 0.5) / H;
    row_cos[size_t(y)] = std::cos(theta);
    row_sin[size_t(y)] = std::sin(theta);
    row_omega[size_t(y)] = (2.0 * kPi / W) * (std::cos(theta0) - std::cos(theta1));
    const double widest =
        theta0 <= 0.5 * kPi && theta1 >= 0.5 * kPi ? 1.0 : std::max(std::sin(theta0), std::sin(theta1));
    row_radius[size_t(y)] = 0.5 * std::hypot(kPi / H, 2.0 * kPi / W * widest);
  }
  std::vector<double> col_sin(cols), col_cos(cols);
  for (int x = 0; x < W; ++x) {
    const double phi = 2.0 * kPi * (x + 0.5) / W;
    col_sin[size_t(x)] = std::sin(phi);
    col_cos[size_t(x)] = std::cos(phi);
  }
  // The map-frame direction of a texel's centre (EnvironmentLight::uv_to_direction).
  const auto centre = [&](int x, int y) {
    return Vec3(row_sin[size_t(y)] * col_sin[size_t(x)], row_cos[size_t(y)], -row_sin[size_t(y)] * col_cos[size_t(x)]);
  };
  // ---- The brightest texel and the map's power.
  double l_max = 0, power = 0;
  int xm = 0, ym = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double l = luminance(env.texel(x, y));
      power += l * row_omega[size_t(y)];
      if (l > l_max) {
        l_max = l;
        xm = x;
        ym = y;
      }
    }
  if (!(l_max > 0) || !(power > 0) || !std::isfinite(power)) return std::nullopt;
  // ---- The sun's texels (kSunCoreRatio, within kSunSearchHalfAngle of the brightest); the axis
  // their power-weighted mean direction (the brightest may lie at the disc's rim), the half-angle
  // the farthest of them from it plus its angular radius.
  const Vec3 seed = centre(xm, ym);
  const double cos_search = std::cos(kSunSearchHalfAngle);
  const auto is_sun = [&](int x, int y) {
    return seed.dot(centre(x, y)) >= cos_search && luminance(env.texel(x, y)) >= kSunCoreRatio * l_max;
  };
  Vec3 sum = Vec3::Zero();
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (is_sun(x, y)) sum += luminance(env.texel(x, y)) * row_omega[size_t(y)] * centre(x, y);
  const Vec3 axis = sum.norm() > 0 ? Vec3(sum.normalized()) : seed;
  double half_angle = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (is_sun(x, y))
        half_angle = std::max(half_angle, std::acos(std::min(axis.dot(centre(x, y)), 1.0)) + row_radius[size_t(y)]);
  if (!(half_angle <= kSunMaxHalfAngle)) return std::nullopt;  // not compact: sky, or a large softbox
  // ---- Then the power of the texels the cone holds.
  const double cos_cone = std::cos(half_angle);
  double cone_power = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (axis.dot(centre(x, y)) >= cos_cone) cone_power += luminance(env.texel(x, y)) * row_omega[size_t(y)];
  const double radiance = cone_power / (2.0 * kPi * (1.0 - cos_cone));
  // An arc through the sun gathers about radiance x 2 half_angle; a half great circle of the
  // mean map, pi x power / (4 pi).
  if (!(radiance * 2.0 * half_angle >= kSunMinArcRatio * power / 4.0)) return std::nullopt;
  EnvironmentSun sun;
  sun.axis = (env.to_world() * axis).normalized();
  sun.half_angle = half_angle;
  sun.radiance = radiance;
  sun.share = std::min(cone_power / power, 1.0);
  return sun;
}

}  // namespace qsil
