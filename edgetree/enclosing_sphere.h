#pragma once
/// @file enclosing_sphere.h
/// Smallest enclosing sphere of a set of 3D points, used to choose the offset direction of a node
/// from its unit plane normals [QSS 4.4, Eq. 7, Appendix G]: if the smallest sphere enclosing the
/// normals has radius < 1, the direction c/|c| to its centre maximises the minimum dot product with
/// every normal.

#include "qsil/math.h"

#include <span>
#include <vector>

namespace qsil::edgetree {

/// A sphere: centre and radius (units of the input points).
struct Sphere {
  Vec3 center = Vec3::Zero();
  double radius = -1.0;  ///< negative: empty sphere
  /// True if p is inside or on the sphere, up to a relative tolerance of 1e-12 of the radius
  /// (the tolerance only affects optimality, never coverage: callers grow the sphere afterwards).
  bool contains(const Vec3& p) const;
};

/// Exact smallest enclosing sphere of `points` by Welzl's algorithm with the move-to-front
/// heuristic (Welzl 1991; Gärtner 1999). Expected O(n). Empty input: radius -1.
/// Degenerate support sets (duplicate, collinear or coplanar points) are handled by falling back
/// to a smaller support set; the result always contains every input point (it is grown if
/// rounding left a point outside).
Sphere min_enclosing_sphere(std::span<const Vec3> points);

/// Approximate smallest enclosing sphere as in [QSS 4.4] (Larsson 2008, "extremal points optimal
/// sphere"): the exact sphere of the extremal points of `points` along 16 fixed directions on a
/// hemisphere (at most 32 points), then grown to cover every point: for a point outside, the new
/// sphere is the smallest one containing the old sphere and the point. Always covers all points;
/// radius at most ~ a few percent above the optimum in practice.
Sphere approx_enclosing_sphere(std::span<const Vec3> points);

/// The 16 fixed unit directions on the upper hemisphere (z >= 0) used by approx_enclosing_sphere.
const std::vector<Vec3>& extremal_directions();

}  // namespace qsil::edgetree
