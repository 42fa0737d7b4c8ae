/// @file quadric_fit.cpp
/// Taubin-style dual quadric fit [QSS 4.3, Eq. 5].

#include "quadric_fit.h"

#include "qsil/edgetree/local_frame.h"

#include <Eigen/Eigenvalues>

#include <vector>

#include <cmath>

namespace qsil::edgetree {

namespace {
using Vec10 = Eigen::Matrix<double, 10, 1>;
using Mat10 = Eigen::Matrix<double, 10, 10>;

// v = [Q00, Q11, Q22, Q33, Q01, Q02, Q03, Q12, Q13, Q23].
Mat4 unpack(const Vec10& v) {
  Mat4 Q;
  Q << v[0], v[4], v[5], v[6],  //
      v[4], v[1], v[7], v[8],   //
      v[5], v[7], v[2], v[9],   //
      v[6], v[8], v[9], v[3];
  return Q;
}

/// The moment matrices of Eq. 5 over the planes (local frame): M = sum s s^T with
/// q^T Q q = v . s(q), and N = sum g g^T with (Q q)_3 = v . g(q) (both filled in full).
void accumulate_moments(std::span<const Vec4> planes, Mat10& M, Mat10& N) {
  // Accumulate the upper triangles of M = sum s s^T and N = sum g g^T by hand (55 + 10
  // products per plane; g has only 4 non-zero entries, at 3, 6, 8, 9).
  M = Mat10::Zero();
  N = Mat10::Zero();
  for (const Vec4& q : planes) {
    double s[10];
    // q^T Q q = v . s(q)
    s[0] = q[0] * q[0];
    s[1] = q[1] * q[1];
    s[2] = q[2] * q[2];
    s[3] = q[3] * q[3];
    s[4] = 2 * q[0] * q[1];
    s[5] = 2 * q[0] * q[2];
    s[6] = 2 * q[0] * q[3];
    s[7] = 2 * q[1] * q[2];
    s[8] = 2 * q[1] * q[3];
    s[9] = 2 * q[2] * q[3];
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i <= j; ++i) M(i, j) += s[i] * s[j];
    // (Q q)_3 = Q30 q0 + Q31 q1 + Q32 q2 + Q33 q3 = v . g(q)
    const int gi[4] = {3, 6, 8, 9};
    const double gv[4] = {q[3], q[0], q[1], q[2]};
    for (int b = 0; b < 4; ++b)
      for (int a = 0; a <= b; ++a) N(gi[a], gi[b]) += gv[a] * gv[b];
  }
  for (int j = 0; j < 10; ++j)
    for (int i = 0; i < j; ++i) {
      M(j, i) = M(i, j);
      N(j, i) = N(i, j);
    }
}

/// Pseudo-inverse of M_uu (normals' monomials; rank-deficient for planar or cylindrical
/// patches), eigenvalues below 1e-12 of the largest dropped, into `pinv`; false if the
/// eigensolver fails.
bool pseudo_inverse(const Eigen::Matrix<double, 6, 6>& Muu, Eigen::Matrix<double, 6, 6>& pinv) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eu(Muu);
  if (eu.info() != Eigen::Success) return false;
  const double emax = eu.eigenvalues().cwiseAbs().maxCoeff();
  Eigen::Matrix<double, 6, 1> inv;
  for (int i = 0; i < 6; ++i) {
    const double e = eu.eigenvalues()[i];
    inv[i] = e > 1e-12 * emax ? 1.0 / e : 0.0;
  }
  pinv = eu.eigenvectors() * inv.asDiagonal() * eu.eigenvectors().transpose();
  return true;
}
}  // namespace

bool fit_dual_quadric(std::span<const Vec4> planes, Mat4* Q) {
  if (planes.empty()) return false;
  Mat10 M, N;
  accumulate_moments(planes, M, N);
  if (!M.allFinite() || !N.allFinite()) return false;

  // N only involves w = v[{3,6,8,9}] (the w-row of Q). Split v = [u, w] with u the other six
  // entries. For a fixed w the numerator v^T M v is minimised by u = -M_uu^+ M_uw w, leaving
  // the 4x4 Schur complement S = M_ww - M_wu M_uu^+ M_uw: minimise w^T S w / w^T N_ww w, the
  // smallest eigenvalue of S w = mu N_ww w with N_ww positive definite for >= 4 general planes.
  // This is Eq. 5 exactly, without the ill-conditioned 10x10 pencil (M is singular whenever an
  // exact fit exists, e.g. planes tangent to one quadric).
  static const int wi[4] = {3, 6, 8, 9}, ui[6] = {0, 1, 2, 4, 5, 7};
  Eigen::Matrix<double, 6, 6> Muu;
  Eigen::Matrix<double, 6, 4> Muw;
  Eigen::Matrix4d Mww, Nww;
  for (int a = 0; a < 6; ++a) {
    for (int b = 0; b < 6; ++b) Muu(a, b) = M(ui[a], ui[b]);
    for (int b = 0; b < 4; ++b) Muw(a, b) = M(ui[a], wi[b]);
  }
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      Mww(a, b) = M(wi[a], wi[b]);
      Nww(a, b) = N(wi[a], wi[b]);
    }
  Eigen::Matrix<double, 6, 6> Muu_pinv;  // M_uu^+
  if (!pseudo_inverse(Muu, Muu_pinv)) return false;
  Eigen::Matrix4d S = Mww - Muw.transpose() * Muu_pinv * Muw;
  S = 0.5 * (S + S.transpose()).eval();
  const double ntr = Nww.trace();
  if (!(ntr > 0.0)) return false;
  Nww.diagonal().array() += 1e-12 * ntr;  // positive definite even for degenerate plane sets
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix4d> solver(
      S, Nww, Eigen::ComputeEigenvectors | Eigen::Ax_lBx);  // S w = mu N w
  if (solver.info() != Eigen::Success) return false;
  const Eigen::Vector4d w = solver.eigenvectors().col(0);  // smallest mu, ascending order
  const Eigen::Matrix<double, 6, 1> u = -Muu_pinv * (Muw * w);
  Vec10 v;
  for (int a = 0; a < 4; ++a) v[wi[a]] = w[a];
  for (int a = 0; a < 6; ++a) v[ui[a]] = u[a];
  Mat4 R = unpack(v);
  const double mx = R.cwiseAbs().maxCoeff();
  if (!(mx > 0.0) || !R.allFinite()) return false;
  *Q = R / mx;
  return true;
}

bool fit_dual_quadric(std::span<const Vec4> planes, const Vec3& center, double scale, Mat4* Q) {
  LocalFrame frame{center, scale};
  std::vector<Vec4> local;
  local.reserve(planes.size());
  for (const Vec4& q : planes) local.push_back(frame.plane(q));
  Mat4 Ql;
  if (!fit_dual_quadric(local, &Ql)) return false;
  const Mat4 K = frame.plane_matrix();
  Mat4 R = K.transpose() * Ql * K;
  const double mx = R.cwiseAbs().maxCoeff();
  if (!(mx > 0.0) || !R.allFinite()) return false;
  *Q = R / mx;
  return true;
}

}  // namespace qsil::edgetree
