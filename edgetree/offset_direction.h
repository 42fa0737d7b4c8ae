#pragma once
/// @file offset_direction.h
/// The offset direction D of a node and the orthonormal basis A = [t1, t2, t3, Z] built from it
/// [QSS 3.2, 4.4, Appendices B and G; docs/architecture.md §5 "Per node"].

#include "qsil/math.h"

#include <span>

namespace qsil::edgetree {

/// Minimum of Z.q / |q| over the planes (Z unit) that we accept before building a dual box:
/// below it the dual box coordinates q/(Z.q) would be ~1/kMinZq times the plane scale and the
/// node is marked unrejectable instead (conservative: it always accepts).
inline constexpr double kMinZq = 1e-7;

/// Result of choose_offset_direction.
struct OffsetDirection {
  enum class Kind {
    Direction,    ///< D = [d, 0], d unit: smallest sphere of the normals has radius < 1 [QSS Eq. 7]
    Point,        ///< D = [P, 1] from the LP [QSS Eq. 6] with rho > 0
    Unrejectable  ///< no D with D.q > 0 for every plane: a silhouette for every point [QSS App. B]
  };
  Kind kind = Kind::Unrejectable;
  Vec4 D = Vec4::Zero();  ///< offset vector (frame of the input planes)
  double min_cos = 0.0;   ///< min over planes of (D.q) / (|D| |q|), > kMinZq when not Unrejectable
  bool used_lp = false;   ///< the LP was solved (the sphere steps found no direction)
};

/// Chooses the offset vector D for the planes P of a patch (unit normals, expressed in the node's
/// local frame: centred, unit size) following [QSS 4.4]: approximate smallest enclosing sphere of
/// the normals (extremal points along 16 directions, Welzl with move-to-front, grown to cover
/// all); if its radius is >= 1, the LP of [QSS Eq. 6]; if the LP is unbounded (a direction
/// exists that the approximate sphere missed) or fails, the exact smallest sphere over every
/// normal. The guard Z.q > kMinZq |q| for every plane (Z = D/|D|) is checked for every
/// outcome; failing it gives Unrejectable.
OffsetDirection choose_offset_direction(std::span<const Vec4> planes);

/// Orthonormal basis A = [t1, t2, t3, Z] of R^4 (columns) whose last column is Z = D/|D|
/// (Householder reflection of the coordinate axis closest to Z). Requires |D| > 0.
Mat4 basis_from_direction(const Vec4& D);

}  // namespace qsil::edgetree
