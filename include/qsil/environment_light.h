#pragma once
/// @file environment_light.h
/// The environment emitter of a scene (qsil::Environment, scene.h): none, a constant radiance,
/// or a lat-long environment map (Mitsuba 3 `envmap`), with importance sampling.
///
/// Env map convention (Mitsuba 3 `envmap`, nearest-texel lookup). In the map's local frame
/// (world = Environment::to_world * local, a rotation), a unit direction d maps to
///   u = atan2(d.x, -d.z) / (2 pi) wrapped to [0,1),   v = acos(d.y) / pi   (v = 0: top row, +y),
/// and conversely d(u,v) = (sin(theta) sin(phi), cos(theta), -sin(theta) cos(phi)) with
/// theta = pi v, phi = 2 pi u. The radiance is the texel containing (u v) (column floor(u W),
/// row floor(v H)), piecewise constant with no filtering, times `scale`; so the sampling density
/// matches the lookup exactly.
///
/// Sampling (pbrt-v4 §12.5.2 "Image Infinite Lights"): a piecewise-constant Distribution2D over
/// (u,v) with weights luminance(texel) * sin(theta at the row centre); the solid-angle density is
/// pdf_omega = pdf_uv / (2 pi^2 sin(theta)) (|d omega| = 2 pi^2 sin(theta) du dv).
///
/// Differentiation (docs/architecture.md §4): an environment lookup depends on direction only, which is
/// detached, so there is nothing to differentiate here (zero derivative).

#include "qsil/math.h"
#include "qsil/sampling.h"
#include "qsil/scene.h"

#include <vector>

namespace qsil {

/// Radiance arriving from the environment, and its importance sampling. Built once per scene;
/// immutable and thread-safe afterwards.
class EnvironmentLight {
 public:
  /// Builds the emitter. For an EnvMap, `env.texels` must have channels R, G, B and
  /// `env.to_world` must be a rotation, and texels must be finite (throws qsil::Error otherwise).
  /// Negative texel channels (ringing in some HDRIs) are clamped to 0 for both lookup and
  /// sampling, so that the density is positive wherever the radiance is non-zero.
  explicit EnvironmentLight(const Environment& env);

  /// False for Environment::Type::None (no environment: escaped rays see black).
  bool present() const { return type_ != Environment::Type::None; }

  /// Radiance arriving at the scene from world direction `dir_world` (unit), i.e. seen when
  /// looking out along dir_world. 0 for None.
  Color eval(const Vec3& dir_world) const;

  /// An importance sample: world direction (unit), the radiance eval(dir), and the solid-angle
  /// density. pdf = 0 marks an invalid sample (no environment, or an all-black map).
  struct Sample {
    Vec3 dir = Vec3::Zero();
    Color radiance = Color::Zero();
    double pdf = 0;
  };
  /// u in [0,1)^2. EnvMap: luminance * sin(theta) weighted texel distribution; Constant: uniform
  /// sphere; None: invalid.
  Sample sample(const Vec2& u) const;

  /// Solid-angle density of sample() at world direction `dir_world` (unit).
  double pdf(const Vec3& dir_world) const;

  /// Mean radiance over the sphere: (1/(4 pi)) integral eval(d) dd. Exact for the
  /// piecewise-constant map (texels weighted by their solid angle).
  Color average_radiance() const;

  /// Map-frame direction (unit) -> (u, v) in [0,1)x[0,1] per the convention above.
  static Vec2 direction_to_uv(const Vec3& d_local);
  /// (u, v) -> unit map-frame direction, the inverse of direction_to_uv.
  static Vec3 uv_to_direction(const Vec2& uv);

  /// Texel resolution of the map (0 x 0 unless EnvMap).
  int width() const { return width_; }
  int height() const { return height_; }
  /// The radiance of texel (x, y) (column x in [0, width()), row y in [0, height()), top row
  /// first), as eval() returns it: scaled, negative channels clamped to 0. EnvMap only.
  Color texel(int x, int y) const { return texels_[size_t(y) * size_t(width_) + size_t(x)].radiance; }
  /// The map's rotation, map frame -> world (identity unless EnvMap).
  const Mat3& to_world() const { return to_world_; }

 private:
  Environment::Type type_ = Environment::Type::None;
  Color constant_ = Color::Zero();
  Mat3 to_world_ = Mat3::Identity();
  int width_ = 0, height_ = 0;
  /// A texel's radiance and its sampling weight side by side (one cache line: eval() and pdf()
  /// of one direction, as an escaped ray's MIS weight asks, read one line where two arrays took
  /// two; tools/bench/bench_envmap.cpp). The weight is a copy of distribution_'s weight of the
  /// texel (pdf() divides it by distribution_.integral(), as Distribution2D::pdf does).
  struct alignas(32) TexelRecord {
    Color radiance;  ///< already scaled, negative channels clamped to 0
    double weight;   ///< luminance(radiance) * sin(theta at the row centre): distribution_'s weight
  };
  std::vector<TexelRecord> texels_;  ///< width*height, row-major, top row first
  Distribution2D distribution_;
  Color average_ = Color::Zero();
};

}  // namespace qsil
