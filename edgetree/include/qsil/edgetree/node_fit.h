#pragma once
/// @file node_fit.h
/// Fitting the dual-space bound of one node of the edge forest: offset direction D, basis A,
/// dual box B_q, fitted quadric Q_f, offsets lambda0/lambda1 and the stored pair
/// A^T Q0 A, A^T Q1 A [QSS 3.2-3.3, 4.2-4.4; docs/architecture.md §5 "Per node"].

#include "qsil/edgetree/edge_set.h"
#include "qsil/edgetree/local_frame.h"
#include "qsil/math.h"

#include <cstdint>
#include <span>

namespace qsil::edgetree {

/// Relative padding of every fitted bound (dual box, lambda range): 1e-9 of the magnitude of the
/// bounded quantities, ~10^7 times double rounding, always widening (conservative).
inline constexpr double kFitPad = 1e-9;

/// Dual-space bound of an inner node, in the node's local frame (local_frame.h): every plane q
/// of a wedge of the patch, expressed locally as q', satisfies Z.q' > 0 and
///   r = first three coordinates of A^T q' / (Z.q')  lies in B_q = [bq_lo, bq_hi]   [QSS 3.2]
///   [r,1]^T G0 [r,1] <= 0 <= [r,1]^T G0 [r,1] + delta                           [QSS 3.3, 4.2]
/// with G0 = A^T Q0 A, A^T Q1 A = G0 + delta e4 e4^T (on the slice Z.q' = 1, Q1 - Q0 =
/// (lambda1 - lambda0) D D^T is the constant delta = (lambda1 - lambda0) |D|^2 >= 0, so storing
/// G0 and delta keeps Q0 <= Q1 exact).
struct NodeBound {
  LocalFrame frame;                     ///< p' = (p - c)/s
  Mat4 A = Mat4::Identity();            ///< orthonormal basis [t1, t2, t3, Z] (columns), local frame
  Vec3 bq_lo = Vec3::Zero();            ///< dual box B_q, lower corner
  Vec3 bq_hi = Vec3::Zero();            ///< dual box B_q, upper corner
  Mat4 G0 = Mat4::Zero();               ///< A^T Q0 A (symmetric); zero for box-only nodes
  double delta = 0.0;                   ///< A^T Q1 A - A^T Q0 A = delta e4 e4^T, delta >= 0
  Vec4 D = Vec4::Zero();                ///< offset vector, local frame ([d,0] or [P,1])
  double lambda0 = 0.0, lambda1 = 0.0;  ///< padded offsets (diagnostics)
  /// A^T Q1 A.
  Mat4 G1() const {
    Mat4 G = G0;
    G(3, 3) += delta;
    return G;
  }
};

/// A wedge: the two face planes of an edge, world frame, [n, -n.x0] with unit n.
struct Wedge {
  Vec4 q0, q1;
};

/// Options of node fitting.
struct NodeFitOptions {
  int min_fit_planes = 15;   ///< fewer distinct planes: inherit the parent's Q_f [QSS code]
  bool fit_quadrics = true;  ///< false: every node is box-only (the "quadric-box" variant)
};

/// Result of fit_node.
struct NodeFit {
  std::uint16_t flags = 0;  ///< kNodeUnrejectable, kNodeBoxOnly, kNodeInherited, kNodeUsedLp
  NodeBound bound;          ///< valid unless kNodeUnrejectable
  bool has_qf = false;      ///< qf is a usable fitted (or inherited) quadric
  Mat4 qf = Mat4::Zero();   ///< Q_f in bound.frame, max |entry| = 1 (children may inherit it)
};

/// Fits the bound of one node from its unique face planes (world frame, unit normals), its
/// wedges (world frame) and its primal box `bp` (sets the local frame). `parent` (may be null)
/// provides the Q_f to inherit when this node has fewer than options.min_fit_planes planes or
/// the fit fails; the inherited quadric gets this node's own D, B_q and lambdas, so the bound
/// stays sound. Degenerate input never throws: it yields an unrejectable or box-only node.
NodeFit fit_node(std::span<const Vec4> planes, std::span<const Wedge> wedges, const Box3& bp, const NodeFit* parent,
                 const NodeFitOptions& options = {});

/// What refit_node did.
enum class NodeRefit {
  Refitted,  ///< dual box and offsets recomputed (a box-only bound: its dual box)
  BoxOnly,   ///< dual box recomputed, the offsets failed: the bound is now box-only
  Failed,    ///< D no longer separates the planes (Z.q <= kMinZq |q| for one, the fit's own
             ///< guard): fit the node anew
};

/// Refits `b`, a bound made by fit_node (box_only: its node is kNodeBoxOnly), to the wedges of
/// its patch after the vertices moved (world frame, same wedges in the same order): keeps the
/// frame, D, A and the quadric Q_f (recovered as A G0 A^T - lambda0 D D^T, A being orthonormal)
/// and recomputes the dual box and the offsets lambda0, lambda1, hence G0 and delta, over the new
/// planes [QSS 3.2, 4.2; Appendix D]. As sound as a fit: every plane of `wedges` satisfies the
/// refitted bound; only its tightness depends on how far the planes moved. After Failed, `b` is
/// unspecified (the caller fits the node anew).
NodeRefit refit_node(std::span<const Wedge> wedges, bool box_only, NodeBound& b);

}  // namespace qsil::edgetree
