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
/// q^T Q q and g those of the w-row of Q q. N only involves the 4 entries w of the w-row of Q,
/// so the minimisation over the other 6 entries u is linear: with the Schur complement
/// S = M_ww - M_wu M_uu^+ M_uw (pseudo-inverse, eigenvalues below 1e-12 of the largest dropped)
/// the w-row is the eigenvector of the smallest mu of S w = mu N_ww w (Eigen's
/// GeneralizedSelfAdjointEigenSolver, Ax_lBx, on 4x4 with N_ww + 1e-12 trace I positive
/// definite), and u = -M_uu^+ M_uw w. This is the reversed pencil's largest sigma = 1/mu without
/// its ill-conditioning (M is singular whenever an exact fit exists, e.g. the tangent planes of
/// one quadric).
/// Fitting happens in the frame where the patch is centred and of unit size (`center`, `scale`:
/// p' = (p - center)/scale) and the result is mapped back with Q = K^T Q' K (K the plane
/// transform of that frame, local_frame.h), so the returned Q is in the frame of the input
/// planes, normalised to max |Q_ij| = 1. Returns false (Q untouched) when a solve fails or the
/// result is not finite.
bool fit_dual_quadric(std::span<const Vec4> planes, const Vec3& center, double scale, Mat4* Q);

/// Same, for planes already in a centred unit-size frame (center 0, scale 1).
bool fit_dual_quadric(std::span<const Vec4> planes, Mat4* Q);

}  // namespace qsil::edgetree
