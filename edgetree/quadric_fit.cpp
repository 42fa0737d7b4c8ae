/// @file quadric_fit.cpp
/// Taubin-style dual quadric fit [QSS 4.3, Eq. 5].

#include "edgetree/quadric_fit.h"

#include "edgetree/local_frame.h"

#include <Eigen/Eigenvalues>

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
}  // namespace

bool fit_dual_quadric(std::span<const Vec4> planes, Mat4* Q) {
  if (planes.empty()) return false;
  // Accumulate the upper triangles of M = sum s s^T and N = sum g g^T by hand (55 + 10
  // products per plane; g has only 4 non-zero entries, at 3, 6, 8, 9).
  Mat10 M = Mat10::Zero(), N = Mat10::Zero();
  for (const Vec4& q : planes) {
    double s[10];
    // q^T Q q = v . s(q)
    s[0] = q[0] * q[0]; s[1] = q[1] * q[1]; s[2] = q[2] * q[2]; s[3] = q[3] * q[3];
    s[4] = 2 * q[0] * q[1]; s[5] = 2 * q[0] * q[2]; s[6] = 2 * q[0] * q[3];
    s[7] = 2 * q[1] * q[2]; s[8] = 2 * q[1] * q[3]; s[9] = 2 * q[2] * q[3];
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i <= j; ++i) M(i, j) += s[i] * s[j];
    // (Q q)_3 = Q30 q0 + Q31 q1 + Q32 q2 + Q33 q3 = v . g(q)
    const int gi[4] = {3, 6, 8, 9};
    const double gv[4] = {q[3], q[0], q[1], q[2]};
    for (int b = 0; b < 4; ++b)
      for (int a = 0; a <= b; ++a) N(gi[a], gi[b]) += gv[a] * gv[b];
  }
  M = M.selfadjointView<Eigen::Upper>();
  N = N.selfadjointView<Eigen::Upper>();
  const double tr = M.trace();
  if (!(tr > 0.0) || !std::isfinite(tr)) return false;
  M.diagonal().array() += 1e-12 * tr / 10.0;
  Eigen::GeneralizedSelfAdjointEigenSolver<Mat10> solver(N, M, Eigen::ComputeEigenvectors |
                                                                   Eigen::ABx_lx);
  if (solver.info() != Eigen::Success) return false;
  const double sigma = solver.eigenvalues()[9];  // ascending order
  if (!(sigma > 0.0) || !std::isfinite(sigma)) return false;
  Mat4 R = unpack(solver.eigenvectors().col(9));
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
