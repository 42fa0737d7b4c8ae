/// @file environment_light.cpp
/// The environment emitter (see include/qsil/environment_light.h for the conventions).

#include "qsil/environment_light.h"

#include "qsil/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace qsil {

namespace {
constexpr double kOneMinusEpsilon = 1.0 - std::numeric_limits<double>::epsilon() / 2;
}  // namespace

Vec2 EnvironmentLight::direction_to_uv(const Vec3& d) {
  double u = std::atan2(d.x(), -d.z()) * (0.5 * kInvPi);
  if (u < 0) u += 1.0;
  if (!(u < 1.0)) u = 0.0;  // -tiny + 1 rounds to 1: wrap
  const double v = std::acos(std::clamp(d.y(), -1.0, 1.0)) * kInvPi;
  return {u, v};
}

Vec3 EnvironmentLight::uv_to_direction(const Vec2& uv) {
  const double theta = kPi * uv.y(), phi = 2.0 * kPi * uv.x();
  const double st = std::sin(theta);
  return {st * std::sin(phi), std::cos(theta), -st * std::cos(phi)};
}

EnvironmentLight::EnvironmentLight(const Environment& env) : type_(env.type) {
  switch (env.type) {
    case Environment::Type::None: return;
    case Environment::Type::Constant:
      constant_ = env.radiance;
      average_ = env.radiance;
      return;
    case Environment::Type::EnvMap: break;
  }

  // ---- validate the map and its frame
  const Image& img = env.texels;
  const std::string where = env.filename.empty() ? std::string("envmap") : env.filename;
  if (img.width <= 0 || img.height <= 0) throw Error(where + ": environment map has no texels");
  const int ch[3] = {img.channel_index("R"), img.channel_index("G"), img.channel_index("B")};
  if (ch[0] < 0 || ch[1] < 0 || ch[2] < 0) throw Error(where + ": environment map needs channels R, G, B");
  if (!std::isfinite(env.scale) || env.scale < 0) throw Error(where + ": envmap scale must be finite and non-negative");
  const Mat3& r = env.to_world;
  if (!((r.transpose() * r - Mat3::Identity()).cwiseAbs().maxCoeff() < 1e-6))
    throw Error(where + ": envmap to_world must be a rotation (no scale or shear)");
  to_world_ = r;

  // ---- texels (scaled, negative channels clamped) and the sampling weights
  width_ = img.width;
  height_ = img.height;
  texels_.resize(size_t(width_) * size_t(height_));
  std::vector<double> weights(texels_.size());
  average_ = Color::Zero();
  const double dphi = 2.0 * kPi / width_;
  for (int y = 0; y < height_; ++y) {
    const double theta0 = kPi * y / height_, theta1 = kPi * (y + 1) / height_;
    const double sin_mid = std::sin(kPi * (y + 0.5) / height_);
    const double texel_solid_angle = dphi * (std::cos(theta0) - std::cos(theta1));
    for (int x = 0; x < width_; ++x) {
      Color c;
      for (int k = 0; k < 3; ++k) {
        const double value = img.at(ch[k], x, y);
        if (!std::isfinite(value))
          throw Error(where + ": non-finite texel at (" + std::to_string(x) + ", " + std::to_string(y) + ")");
        c[k] = std::max(0.0, value) * env.scale;
      }
      const size_t i = size_t(y) * size_t(width_) + size_t(x);
      weights[i] = luminance(c) * sin_mid;
      texels_[i] = {c, weights[i]};
      average_ += c * texel_solid_angle;
    }
  }
  average_ /= 4.0 * kPi;
  distribution_ = Distribution2D(weights, width_, height_);
}

Color EnvironmentLight::eval(const Vec3& dir_world) const {
  switch (type_) {
    case Environment::Type::None: return Color::Zero();
    case Environment::Type::Constant: return constant_;
    case Environment::Type::EnvMap: break;
  }
  const Vec2 uv = direction_to_uv(to_world_.transpose() * dir_world);
  const int x = std::min(int(uv.x() * width_), width_ - 1);
  const int y = std::min(int(uv.y() * height_), height_ - 1);
  return texel(x, y);
}

EnvironmentLight::Sample EnvironmentLight::sample(const Vec2& u) const {
  Sample s;
  switch (type_) {
    case Environment::Type::None: return s;
    case Environment::Type::Constant:
      s.dir = square_to_uniform_sphere(u);
      s.radiance = constant_;
      s.pdf = uniform_sphere_pdf();
      return s;
    case Environment::Type::EnvMap: break;
  }
  const Distribution2D::Sample ds = distribution_.sample(u);
  if (!(ds.pdf > 0)) return s;  // all-black map: nothing to sample
  const Vec3 d_local = uv_to_direction(ds.p);
  // sin(theta) from the direction itself, as pdf() computes it, so both agree to rounding.
  const double sin_theta = std::hypot(d_local.x(), d_local.z());
  if (!(sin_theta > 0)) return s;  // a pole: measure zero
  s.dir = to_world_ * d_local;
  s.radiance = texel(ds.iu, ds.iv);  // the texel that was sampled (no re-lookup rounding)
  s.pdf = ds.pdf / (2.0 * kPi * kPi * sin_theta);
  return s;
}

double EnvironmentLight::pdf(const Vec3& dir_world) const {
  switch (type_) {
    case Environment::Type::None: return 0.0;
    case Environment::Type::Constant: return uniform_sphere_pdf();
    case Environment::Type::EnvMap: break;
  }
  const Vec3 d_local = to_world_.transpose() * dir_world;
  const double sin_theta = std::hypot(d_local.x(), d_local.z()) / d_local.norm();
  if (!(sin_theta > 0)) return 0.0;
  Vec2 uv = direction_to_uv(d_local.normalized());
  uv = uv.cwiseMin(kOneMinusEpsilon);  // v = 1 at the south pole belongs to the bottom row
  // distribution_.pdf(uv), with the weight read from the texel's record (the line eval() reads).
  if (distribution_.is_zero() || !(uv.x() >= 0.0 && uv.x() < 1.0 && uv.y() >= 0.0 && uv.y() < 1.0)) return 0.0;
  const int x = std::min(int(uv.x() * width_), width_ - 1);
  const int y = std::min(int(uv.y() * height_), height_ - 1);
  const double pdf_uv = texels_[size_t(y) * size_t(width_) + size_t(x)].weight / distribution_.integral();
  return pdf_uv / (2.0 * kPi * kPi * sin_theta);
}

Color EnvironmentLight::average_radiance() const { return average_; }

}  // namespace qsil
