#pragma once
/// @file dual.h
/// Forward-mode dual numbers for the interior term (docs/architecture.md §4): Eigen's AutoDiffScalar with a
/// fixed-size derivative vector of N entries, one per geometry parameter (N in {1,2,4,8}; a run
/// with K parameters uses the smallest N >= K). A well-kept library type rather than our own: its
/// expression templates avoid temporaries, it works inside Eigen vectors (Vec3T<Dual<N>>), and a
/// fixed size keeps every derivative vector on the stack.
///
/// `value()` reads the value of a scalar, vector or colour whether it holds doubles (primal
/// rendering) or duals: it drops the derivatives, which is how every sampled direction, pdf and
/// MIS weight is detached (docs/architecture.md §4). `lift()` goes the other way.

#include "qsil/check.h"
#include "qsil/math.h"

#include <unsupported/Eigen/AutoDiff>

#include <type_traits>

namespace qsil {

/// Dual number with N derivative entries.
template <int N>
using Dual = Eigen::AutoDiffScalar<Eigen::Matrix<double, N, 1>>;

/// Largest number of parameters differentiated in one run.
inline constexpr int kMaxParameters = 8;

/// Calls `f(std::integral_constant<int, N>{})` with N the dual size for `num_params` parameters:
/// the smallest of 1, 2, 4, 8 that is >= num_params. The one dispatch from a run-time parameter
/// count to the compile-time derivative size. num_params must be in 1..kMaxParameters (checked:
/// parameter lists are validated by check_parameter_count first).
template <class F>
decltype(auto) with_dual_size(int num_params, F&& f) {
  QSIL_CHECK(num_params >= 1 && num_params <= kMaxParameters);
  if (num_params == 1) return f(std::integral_constant<int, 1>{});
  if (num_params == 2) return f(std::integral_constant<int, 2>{});
  if (num_params <= 4) return f(std::integral_constant<int, 4>{});
  return f(std::integral_constant<int, 8>{});
}

inline double value(double x) { return x; }
template <int N>
inline double value(const Dual<N>& x) {
  return x.value();
}

template <class T>
inline Vec3 value(const Vec3T<T>& v) {
  return Vec3(value(v.x()), value(v.y()), value(v.z()));
}
inline const Vec3& value(const Vec3& v) { return v; }
template <class T>
inline Color value(const ColorT<T>& c) {
  return Color(value(c.x()), value(c.y()), value(c.z()));
}
inline const Color& value(const Color& c) { return c; }

/// Lifts a double vector to scalar type T with zero derivatives.
template <class T>
inline Vec3T<T> lift(const Vec3& v) {
  return Vec3T<T>(T(v.x()), T(v.y()), T(v.z()));
}
template <class T>
inline ColorT<T> lift(const Color& c) {
  return ColorT<T>(T(c.x()), T(c.y()), T(c.z()));
}

/// Lifts position x with per-parameter velocities dx/dtheta_k (columns of vel, 3 x N) to a dual.
template <int N>
inline Vec3T<Dual<N>> lift(const Vec3& x, const Eigen::Matrix<double, 3, N>& vel) {
  Vec3T<Dual<N>> r;
  for (int i = 0; i < 3; ++i) r[i] = Dual<N>(x[i], vel.row(i).transpose());
  return r;
}

}  // namespace qsil
