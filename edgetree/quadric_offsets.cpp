/// @file quadric_offsets.cpp
/// Closed-form lambda range over a wedge [QSS 4.2, Appendix D].

#include "quadric_offsets.h"

#include <algorithm>
#include <cmath>

namespace qsil::edgetree {

double plane_lambda(const Mat4& Qf, const Vec4& D, const Vec4& q) {
  const double dq = D.dot(q);
  return -q.dot(Qf * q) / (dq * dq);
}

Vec2 wedge_lambda_range(const Mat4& Qf, const Vec4& D, const Vec4& q0, const Vec4& q1) {
  const Vec4 dq = q1 - q0;
  const Vec4 Qq0 = Qf * q0;
  const double f0 = q0.dot(Qq0);
  const double f1 = 2.0 * dq.dot(Qq0);
  const double f2 = dq.dot(Qf * dq);
  const double a = D.dot(q0), b = D.dot(dq);
  const double l0 = -f0 / (a * a);
  const double l1 = plane_lambda(Qf, D, q1);
  Vec2 r(std::min(l0, l1), std::max(l0, l1));
  const double num = 2.0 * b * f0 - a * f1;
  const double den = 2.0 * f2 * a - b * f1;
  if (den != 0.0) {
    const double t = num / den;
    if (t > 0.0 && t < 1.0) {
      const double w = a + b * t;
      const double ls = -((f2 * t + f1) * t + f0) / (w * w);
      r[0] = std::min(r[0], ls);
      r[1] = std::max(r[1], ls);
    }
  }
  return r;
}

bool appendix_d_lambda_star(const Mat4& Qf, const Vec4& D, const Vec4& q0, const Vec4& q1, double* lambda_star) {
  const double f00 = q0.dot(Qf * q0), f11 = q1.dot(Qf * q1), f01 = q0.dot(Qf * q1);
  const double d0 = D.dot(q0), d1 = D.dot(q1);
  const double o00 = d0 * d0, o11 = d1 * d1, o01 = d0 * d1;
  const double den = f00 * o11 + o00 * f11 - 2.0 * f01 * o01;
  if (den == 0.0) return false;
  const double ls = (f01 * f01 - f00 * f11) / den;
  const Mat4 Qs = Qf + ls * D * D.transpose();
  const Vec4 dq = q0 - q1;
  if (q0.dot(Qs * q1) * dq.dot(Qs * dq) < 0.0) {
    *lambda_star = ls;
    return true;
  }
  return false;
}

}  // namespace qsil::edgetree
