#pragma once
/// @file local_frame.h
/// The local frame of a node: primal points p' = (p - c) / s with c the centre and s the
/// half-diagonal of the patch's box. Dual data of a node (planes, D, A, B_q, quadrics) are stored
/// in this frame for floating-point conditioning (a mesh translated by 1e4 or scaled by 1e-4 gives
/// the same local numbers). Fitting is invariant under this similarity in exact arithmetic
/// [QSS 4.3; docs/architecture.md §5 "Fitted dual quadric"].

#include "qsil/math.h"

namespace qsil::edgetree {

/// Similarity p' = (p - center) / scale, scale > 0 (scene units).
struct LocalFrame {
  Vec3 center = Vec3::Zero();
  double scale = 1.0;

  /// Homogeneous local point [(p - c)/s, 1] of a world point p.
  Vec4 point(const Vec3& p) const {
    Vec4 x;
    x << (p - center) / scale, 1.0;
    return x;
  }
  /// Plane transform K: q' = K q maps a world plane [n, w] to the local plane [n, (n.c + w)/s]
  /// with the same unit normal, so that q'.x' = (q.x) / s for every point (signs preserved).
  Mat4 plane_matrix() const {
    Mat4 K = Mat4::Identity();
    K.block<1, 3>(3, 0) = center.transpose() / scale;
    K(3, 3) = 1.0 / scale;
    return K;
  }
  /// Inverse of plane_matrix(): q = K^-1 q'.
  Mat4 plane_matrix_inverse() const {
    Mat4 Ki = Mat4::Identity();
    Ki.block<1, 3>(3, 0) = -center.transpose();
    Ki(3, 3) = scale;
    return Ki;
  }
  /// Local plane of a world plane q = [n, w]: [n, (n.c + w) / s].
  Vec4 plane(const Vec4& q) const {
    Vec4 r = q;
    r[3] = (q.head<3>().dot(center) + q[3]) / scale;
    return r;
  }
  /// Frame of a box: centre and half-diagonal (1 if the box is a point or empty).
  static LocalFrame of_box(const Box3& b) {
    LocalFrame f;
    if (b.empty()) return f;
    f.center = b.center();
    const double h = 0.5 * b.diagonal();
    f.scale = h > 0.0 && std::isfinite(h) ? h : 1.0;
    return f;
  }
};

/// Re-expresses a dual quadric given in frame `from` in frame `to`: with q_from = M q_to,
/// M = K_from K_to^-1, the quadric is M^T Q M (q^T Q q is then the same number for the same plane
/// up to the positive factors of the normalisation).
inline Mat4 transfer_dual_quadric(const Mat4& Q, const LocalFrame& from, const LocalFrame& to) {
  const Mat4 M = from.plane_matrix() * to.plane_matrix_inverse();
  return M.transpose() * Q * M;
}

}  // namespace qsil::edgetree
