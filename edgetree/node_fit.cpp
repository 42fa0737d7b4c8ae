/// @file node_fit.cpp
/// One node's dual bound [QSS 3.2-3.3, 4.2-4.4].

#include "qsil/edgetree/node_fit.h"

#include "offset_direction.h"
#include "quadric_fit.h"
#include "quadric_offsets.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace qsil::edgetree {

namespace {

/// The dual box B_q [QSS 3.2] of the local-frame planes `local` in the basis b.A, padded, into
/// b.bq_lo, b.bq_hi; false (the node is unrejectable) if a plane has Z.q <= 0 or it is not finite.
bool fit_dual_box(std::span<const Vec4> local, NodeBound& b) {
  const Vec4 Z = b.A.col(3);
  // The endpoints suffice (central projection maps each wedge segment into the hull of its
  // endpoints' images).
  b.bq_lo = Vec3::Constant(kInf);
  b.bq_hi = Vec3::Constant(-kInf);
  for (const Vec4& q : local) {
    const double zq = Z.dot(q);
    if (!(zq > 0.0)) return false;  // cannot happen after the guard; stay sound if it does
    const Vec3 r = (b.A.transpose() * q).head<3>() / zq;
    b.bq_lo = b.bq_lo.cwiseMin(r);
    b.bq_hi = b.bq_hi.cwiseMax(r);
  }
  const double rmag = std::max(b.bq_lo.cwiseAbs().maxCoeff(), b.bq_hi.cwiseAbs().maxCoeff());
  if (!std::isfinite(rmag)) return false;
  const double pad = kFitPad * (rmag + 1.0);
  b.bq_lo.array() -= pad;
  b.bq_hi.array() += pad;
  return true;
}

/// The node's quadric Q_f in out.bound.frame [QSS 4.3] into `qf`: fitted to the local planes if
/// there are at least options.min_fit_planes, else the parent's (max |entry| = 1, kNodeInherited).
/// Sets out.has_qf and out.qf; false: none (the node is box-only).
bool node_quadric(std::span<const Vec4> local, const NodeFit* parent, const NodeFitOptions& options, NodeFit& out,
                  Mat4& qf) {
  bool have = false;
  if (int(local.size()) >= options.min_fit_planes) have = fit_dual_quadric(local, &qf);
  if (have) {
    out.has_qf = true;
    out.qf = qf;
  } else if (parent && parent->has_qf) {
    qf = transfer_dual_quadric(parent->qf, parent->bound.frame, out.bound.frame);
    const double mx = qf.cwiseAbs().maxCoeff();
    if (mx > 0.0 && qf.allFinite()) {
      qf /= mx;
      have = true;
      out.flags |= kNodeInherited;
      out.has_qf = true;
      out.qf = qf;
    }
  }
  return have;
}

/// The offsets lambda0, lambda1 of Q_f along b.D over every wedge [QSS 4.2, Appendix D], padded,
/// and from them b.G0 = A^T Q0 A and b.delta (local frame); `wedge_planes` holds each wedge's two
/// planes in b.frame, in turn (q0, q1, q0, q1, ...). False: the node must be box-only (b.G0 and
/// b.delta then zero).
bool fit_offsets(const Mat4& qf, std::span<const Vec4> wedge_planes, NodeBound& b) {
  const Vec4& D = b.D;
  double l0 = kInf, l1 = -kInf, lscale = 0.0;
  const double qmax = qf.cwiseAbs().maxCoeff();
  for (size_t i = 0; i + 1 < wedge_planes.size(); i += 2) {
    const Vec4& q0 = wedge_planes[i];
    const Vec4& q1 = wedge_planes[i + 1];
    const double d0 = D.dot(q0), d1 = D.dot(q1);
    if (!(d0 > 0.0 && d1 > 0.0)) return false;
    const Vec2 r = wedge_lambda_range(qf, D, q0, q1);
    l0 = std::min(l0, r[0]);
    l1 = std::max(l1, r[1]);
    // Magnitude of lambda's terms on the wedge: |Qf| |q|_1^2 / (D.q)^2 (D.q is linear in t,
    // so its minimum over the wedge is at an endpoint).
    const double qn = std::max(q0.cwiseAbs().sum(), q1.cwiseAbs().sum());
    const double dmin = std::min(d0, d1);
    lscale = std::max(lscale, qmax * qn * qn / (dmin * dmin));
  }
  if (!(std::isfinite(l0) && std::isfinite(l1) && std::isfinite(lscale))) return false;
  const double lpad = kFitPad * (lscale + std::max(std::abs(l0), std::abs(l1)));
  l0 -= lpad;
  l1 += lpad;
  b.lambda0 = l0;
  b.lambda1 = l1;
  const Mat4 Q0 = qf + l0 * D * D.transpose();
  b.G0 = b.A.transpose() * Q0 * b.A;
  b.G0 = 0.5 * (b.G0 + b.G0.transpose()).eval();
  b.delta = (l1 - l0) * D.squaredNorm();
  if (!b.G0.allFinite() || !std::isfinite(b.delta) || !(b.delta >= 0.0)) {
    b.G0.setZero();
    b.delta = 0.0;
    return false;
  }
  return true;
}

}  // namespace

NodeFit fit_node(std::span<const Vec4> planes, std::span<const Wedge> wedges, const Box3& bp, const NodeFit* parent,
                 const NodeFitOptions& options) {
  NodeFit out;
  NodeBound& b = out.bound;
  b.frame = LocalFrame::of_box(bp);
  if (planes.empty() || wedges.empty()) {
    out.flags |= kNodeUnrejectable;
    return out;
  }
  std::vector<Vec4> local;
  local.reserve(planes.size());
  for (const Vec4& q : planes) local.push_back(b.frame.plane(q));

  // ---- offset direction D and basis A [QSS 4.4]
  const OffsetDirection od = choose_offset_direction(local);
  if (od.used_lp) out.flags |= kNodeUsedLp;
  if (od.kind == OffsetDirection::Kind::Unrejectable) {
    out.flags |= kNodeUnrejectable;
    return out;
  }
  b.D = od.D;
  b.A = basis_from_direction(od.D);

  // ---- dual box B_q [QSS 3.2]
  if (!fit_dual_box(local, b)) {
    out.flags |= kNodeUnrejectable;
    return out;
  }

  // ---- fitted quadric Q_f [QSS 4.3], or the parent's, or none
  Mat4 qf;
  if (!options.fit_quadrics || !node_quadric(local, parent, options, out, qf)) {
    out.flags |= kNodeBoxOnly;
    return out;
  }

  // ---- offsets lambda0, lambda1 over every wedge [QSS 4.2, Appendix D]
  std::vector<Vec4> wedge_planes;
  wedge_planes.reserve(2 * wedges.size());
  for (const Wedge& w : wedges) {
    wedge_planes.push_back(b.frame.plane(w.q0));
    wedge_planes.push_back(b.frame.plane(w.q1));
  }
  if (!fit_offsets(qf, wedge_planes, b)) out.flags |= kNodeBoxOnly;
  return out;
}

NodeRefit refit_node(std::span<const Wedge> wedges, bool box_only, NodeBound& b) {
  if (wedges.empty()) return NodeRefit::Failed;
  // The quadric the offsets were fitted for, before the dual box overwrites nothing of it.
  Mat4 qf = Mat4::Zero();
  if (!box_only) {
    qf = b.A * b.G0 * b.A.transpose() - b.lambda0 * b.D * b.D.transpose();
    qf = 0.5 * (qf + qf.transpose()).eval();
    const double mx = qf.cwiseAbs().maxCoeff();
    if (!(mx > 0.0) || !qf.allFinite()) return NodeRefit::Failed;
    qf /= mx;
  }
  thread_local std::vector<Vec4> local;
  local.clear();
  for (const Wedge& w : wedges) {
    local.push_back(b.frame.plane(w.q0));
    local.push_back(b.frame.plane(w.q1));
  }
  // The fit's own guard (choose_offset_direction): every plane at least kMinZq off the slice's
  // horizon, or the node is fitted anew.
  const Vec4 Z = b.A.col(3);
  for (const Vec4& q : local)
    if (!(Z.dot(q) > kMinZq * q.norm())) return NodeRefit::Failed;
  if (!fit_dual_box(local, b)) return NodeRefit::Failed;
  if (box_only) return NodeRefit::Refitted;
  return fit_offsets(qf, local, b) ? NodeRefit::Refitted : NodeRefit::BoxOnly;
}

}  // namespace qsil::edgetree
