#pragma once
/// @file dual.h
/// Forward-mode dual numbers for the interior term (docs/architecture.md §4): Eigen's AutoDiffScalar with a
/// fixed-size derivative vector of N entries, one per geometry parameter (N in {1,2,4,8}; a run
/// with K parameters uses the smallest N >= K). A well-kept library type rather than our own: its
/// expression templates avoid temporaries, it works inside Eigen vectors (Vec3T<Dual<N>>), and a
/// fixed size keeps every derivative vector on the stack.
///
/// `value()` and `derivatives()` read a scalar whether it is a double (primal rendering) or a
/// dual; `detach()` drops the derivative: used for every sampled direction, pdf and MIS weight.

#include "qsil/math.h"

#include <unsupported/Eigen/AutoDiff>

namespace qsil {

/// Dual number with N derivative entries.
template <int N> using Dual = Eigen::AutoDiffScalar<Eigen::Matrix<double, N, 1>>;

/// Largest number of parameters differentiated in one run.
inline constexpr int kMaxParameters = 8;

template <class T> struct DualTraits {
  static constexpr int size = 0;
};
template <int N> struct DualTraits<Dual<N>> {
  static constexpr int size = N;
};

inline double value(double x) { return x; }
template <int N> inline double value(const Dual<N>& x) { return x.value(); }

template <class T> inline Vec3 value(const Vec3T<T>& v) { return Vec3(value(v.x()), value(v.y()), value(v.z())); }
inline const Vec3& value(const Vec3& v) { return v; }
template <class T> inline Color value(const ColorT<T>& c) { return Color(value(c.x()), value(c.y()), value(c.z())); }
inline const Color& value(const Color& c) { return c; }

/// A double or dual with the given value and zero derivatives.
template <class T> inline T constant(double x) { return T(x); }

/// Lifts a double vector to scalar type T with zero derivatives.
template <class T> inline Vec3T<T> lift(const Vec3& v) { return Vec3T<T>(T(v.x()), T(v.y()), T(v.z())); }
template <class T> inline ColorT<T> lift(const Color& c) { return ColorT<T>(T(c.x()), T(c.y()), T(c.z())); }

/// Lifts position x with per-parameter velocities dx/dtheta_k (columns of vel, 3 x N) to a dual.
template <int N> inline Vec3T<Dual<N>> lift(const Vec3& x, const Eigen::Matrix<double, 3, N>& vel) {
  Vec3T<Dual<N>> r;
  for (int i = 0; i < 3; ++i) r[i] = Dual<N>(x[i], vel.row(i).transpose());
  return r;
}

}  // namespace qsil
