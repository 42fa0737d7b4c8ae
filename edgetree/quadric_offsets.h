#pragma once
/// @file quadric_offsets.h
/// Offsets lambda0 <= lambda1 of the bounding quadric pair Q_i = Q_f + lambda_i D D^T
/// [QSS 4.2, Appendix D]. All quantities are in one common frame (a node's local frame).

#include "qsil/math.h"

namespace qsil::edgetree {

/// lambda(q) = -(q^T Qf q) / (D.q)^2 [QSS 4.2]: the offset at which Q_f + lambda D D^T contains q.
/// Requires D.q != 0.
double plane_lambda(const Mat4& Qf, const Vec4& D, const Vec4& q);

/// Minimum and maximum of lambda(q(t)) over the wedge q(t) = (1-t) q0 + t q1, t in [0,1], in
/// closed form; requires D.q0 > 0 and D.q1 > 0 (then D.q(t) > 0 on the whole wedge).
/// With f(t) = q(t)^T Qf q(t) = f2 t^2 + f1 t + f0 and D.q(t) = a + b t, the derivative of
/// lambda = -f / (a + b t)^2 vanishes where (2 f2 a - b f1) t + (a f1 - 2 b f0) = 0: one
/// interior critical point t* at most, whose value is the extremum lambda* of [QSS Appendix D]
/// (the same number; see appendix_d_lambda_star). Returns {min, max} (unpadded).
Vec2 wedge_lambda_range(const Mat4& Qf, const Vec4& D, const Vec4& q0, const Vec4& q1);

/// The closed form of [QSS Appendix D]:
///   lambda* = ((qf01)^2 - qf00 qf11) / (qf00 qo11 + qo00 qf11 - 2 qf01 qo01),
/// with qf_ij = q_i^T Qf q_j and qo_ij = q_i^T D D^T q_j. Returns true and sets *lambda_star when
/// it is an interior extremum of the wedge, i.e. (q0^T Q* q1)(dq^T Q* dq) < 0 with
/// Q* = Qf + lambda* D D^T and dq = q0 - q1. Used by the tests to cross-check
/// wedge_lambda_range.
bool appendix_d_lambda_star(const Mat4& Qf, const Vec4& D, const Vec4& q0, const Vec4& q1, double* lambda_star);

}  // namespace qsil::edgetree
