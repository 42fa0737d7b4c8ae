#pragma once
/// @file quadric_fit.h
/// Fitting a dual quadric to a set of planes [QSS 4.3, Eq. 5, Appendix E].

#include "qsil/math.h"

#include <span>

namespace qsil::edgetree {

/// Fits the dual quadric Q (symmetric 4x4) minimising
///   E(Q) = sum_q (q^T Q q)^2 / sum_q q^T Q A Q q,   A = diag(0,0,0,1)    [QSS Eq. 5]
/// over the planes q = [n, w] (unit n). Q is written as the 10-vector v (4 diagonal entries, then
/// the 6 off-diagonal ones); M = sum s(q) s(q)^T and N = sum g(q) g(q)^T with s the monomials of
/// q^T Q q and g those of the w-row of Q q. N has rank <= 4, so we solve the reversed pencil
/// N v = sigma M v for its largest sigma (= 1 / min E) with Eigen's
/// GeneralizedSelfAdjointEigenSolver, after regularising M by 1e-12 trace(M)/10 I so it is
/// positive definite (a singular M means an exact fit exists; the regulariser picks the exact fit
/// of smallest norm). Fitting happens in the frame where the patch is centred and of unit size
/// (`center`, `scale`: p' = (p - center)/scale) and the result is mapped back with
/// Q = K^T Q' K (K the plane transform of that frame), so the returned Q is in the frame of the
/// input planes, normalised to max |Q_ij| = 1.
/// Returns false (Q untouched) when sigma is not finite and positive or Q is not finite.
bool fit_dual_quadric(std::span<const Vec4> planes, const Vec3& center, double scale, Mat4* Q);

/// Same, for planes already in a centred unit-size frame (center 0, scale 1).
bool fit_dual_quadric(std::span<const Vec4> planes, Mat4* Q);

}  // namespace qsil::edgetree
