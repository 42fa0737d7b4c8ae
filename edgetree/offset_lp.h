#pragma once
/// @file offset_lp.h
/// The linear program of [QSS Eq. 6] for the offset point D of a node (the only interface to
/// CLP; offset_lp.cpp is the only file that includes it, docs/architecture.md §1).

#include "qsil/math.h"

#include <span>

namespace qsil::edgetree {

/// Outcome of the offset LP.
struct OffsetLpResult {
  enum class Status {
    Optimal,     ///< finite optimum: `rho` and `point` are valid
    Unbounded,   ///< rho grows without bound: a direction d with d.n > 0 for all normals exists
    Infeasible,  ///< no solution (cannot happen for a non-empty plane set: rho is free)
    Failed       ///< the solver stopped for another reason (numerical trouble, limits)
  };
  Status status = Status::Failed;
  double rho = 0.0;           ///< max over points of min_q q.[point,1] (units of the planes)
  Vec3 point = Vec3::Zero();  ///< maximiser (same frame as the planes)
  int solves = 0;             ///< LP solves made (diagnostics: constraint generation's rounds)
};

/// Solves [QSS Eq. 6]: variables rho, D = [Dx, Dy, Dz, 1]; maximise rho subject to
/// q.D >= rho for every plane q = [n, w] (unit n). Geometrically: the point farthest inside all
/// planes (largest minimum signed distance rho). rho <= 0 means no point is in front of every
/// plane, so a connected patch has a silhouette for every shading point [QSS Appendix B].
/// The planes should be expressed in a frame where the patch is centred and of unit size, for
/// conditioning. Uses CLP's primal simplex with logging off.
OffsetLpResult solve_offset_lp(std::span<const Vec4> planes);

}  // namespace qsil::edgetree
