#pragma once
/// @file math.h
/// Basic math types of qsil: double-precision Eigen vectors for geometry, RGB colours, constants,
/// and the orthonormal shading frame. Geometry predicates and node fitting are in double
/// (docs/architecture.md §3 "Precision"); only Embree works in float.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace qsil {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec4 = Eigen::Vector4d;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
/// Linear RGB radiance or reflectance, in the scene's RGB units.
using Color = Eigen::Array3d;

/// Rec. 709 / sRGB luminance of linear RGB r, g, b: 0.2126 r + 0.7152 g + 0.0722 b (the weight
/// Mitsuba 3 and pbrt-v4 use for env maps). The one luminance of qsil: env-map sampling weights,
/// light weights of the boundary term's importance, previews and comparison maps.
inline double luminance(double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }

/// Generic 3-vector and colour over a scalar type T (double, or a dual number in forward mode).
template <class T>
using Vec3T = Eigen::Matrix<T, 3, 1>;
/// A 2-vector over scalar type T (film positions over duals).
template <class T>
using Vec2T = Eigen::Matrix<T, 2, 1>;
template <class T>
using ColorT = Eigen::Array<T, 3, 1>;

/// luminance(r, g, b) of a colour.
inline double luminance(const Color& c) { return luminance(c[0], c[1], c[2]); }

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kInvPi = 1.0 / kPi;
inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Axis-aligned box in 3D (scene units). An empty box has lo = +inf, hi = -inf.
struct Box3 {
  Vec3 lo = Vec3::Constant(kInf);
  Vec3 hi = Vec3::Constant(-kInf);
  void expand(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void expand(const Box3& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  bool empty() const { return (lo.array() > hi.array()).any(); }
  /// True iff this box and b (closed) lie within `gap` of each other on every axis, evaluated in
  /// double (lo <= b.hi + gap and b.lo <= hi + gap); gap 0: they overlap.
  bool within(const Box3& b, double gap = 0.0) const {
    return (lo.array() <= b.hi.array() + gap).all() && (b.lo.array() <= hi.array() + gap).all();
  }
  Vec3 center() const { return 0.5 * (lo + hi); }
  Vec3 extent() const { return hi - lo; }
  double diagonal() const { return empty() ? 0.0 : extent().norm(); }
  /// Largest absolute coordinate of the box: the scale of floating-point error near it.
  double max_abs() const { return empty() ? 0.0 : std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff()); }
};

/// Orthonormal frame (s, t, n) built from a unit normal n (Duff et al. 2017, "Building an
/// orthonormal basis, revisited"). Works for double and for dual numbers.
template <class T>
struct FrameT {
  Vec3T<T> s, t, n;
  FrameT() = default;
  explicit FrameT(const Vec3T<T>& nn) : n(nn) {
    using std::copysign;
    const T sign = nn.z() >= 0.0 ? T(1.0) : T(-1.0);
    const T a = T(-1.0) / (sign + nn.z());
    const T b = nn.x() * nn.y() * a;
    s = Vec3T<T>(T(1.0) + sign * nn.x() * nn.x() * a, sign * b, -sign * nn.x());
    t = Vec3T<T>(b, sign + nn.y() * nn.y() * a, -nn.y());
  }
  Vec3T<T> to_local(const Vec3T<T>& v) const { return Vec3T<T>(v.dot(s), v.dot(t), v.dot(n)); }
  Vec3T<T> to_world(const Vec3T<T>& v) const { return s * v.x() + t * v.y() + n * v.z(); }
};
using Frame = FrameT<double>;

}  // namespace qsil
