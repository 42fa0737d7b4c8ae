#pragma once
/// @file conic.h
/// Plane conics and convex polygons for the interior step of the rejection test
/// [QSS Appendix C]. Points are 2D; conics are symmetric 3x3 matrices C acting on homogeneous
/// points y = [a1, a2, 1]: the conic is {y : y^T C y = 0}.

#include "qsil/math.h"

#include <array>
#include <span>

namespace qsil::edgetree {

/// Relative tolerance of the conic computations: a discriminant down to -kConicTol times the
/// magnitude of its terms counts as zero (a tangent line), so near-degenerate real conics are
/// found (leaning toward accept, docs/architecture.md §5).
inline constexpr double kConicTol = 1e-9;

/// Finds finite real points of the conic C following [QSS Appendix C]: intersect it with the
/// line l through r = (0,0) with direction (1,0) and, if needed, with the polar line l' = C r.
/// If the conic has real points, l or l' meets it (Appendix C proves it); points at infinity are
/// not reported. Writes up to 4 points to `out` and returns how many. Returns 0 only if neither
/// line meets the conic within the tolerance. The caller expresses the conic in coordinates whose
/// origin is the point r it wants (e.g. a polygon's centroid).
int find_conic_points(const Mat3& C, std::array<Vec2, 4>* out);

/// Value y^T C y of the conic at the finite point a (y = [a, 1]).
inline double conic_value(const Mat3& C, const Vec2& a) {
  return C(0, 0) * a.x() * a.x() + C(1, 1) * a.y() * a.y() + C(2, 2) +
         2.0 * (C(0, 1) * a.x() * a.y() + C(0, 2) * a.x() + C(1, 2) * a.y());
}

/// True if `a` is inside or on the convex polygon `poly` (vertices in counter-clockwise or
/// clockwise order, at least 3), with a relative tolerance of 1e-9 of the edge lengths and
/// distances that leans toward inside. Fewer than 3 vertices: false.
bool point_in_convex_polygon(std::span<const Vec2> poly, const Vec2& a);

}  // namespace qsil::edgetree
