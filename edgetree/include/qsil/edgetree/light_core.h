#pragma once
/// @file light_core.h
/// The core of a light contour set: the cone of the brightest small light a shading point
/// sees (contour_set.h "Light contour sets"), where the contour probe looks for edges.

#include "qsil/edgetree/contour_set.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/math.h"

#include <array>
#include <cmath>

namespace qsil::edgetree {

/// The core of a light contour set (qsil/edgetree/contour_set.h "Light contour sets") for query
/// q, written into `probe` (axis, cos_half_angle, to_cosine, cos_core): of the quad lights of q
/// and the quads that stand for its light spheres (light_billboard), those that emit toward p
/// (light_toward) and reach above p's shading horizon, the one with
/// the largest radiance × area × |cos at the light| / distance² (from its centre), bounded by the
/// circular cone about the direction to its centre through its farthest corner (a cap under π/2
/// holds the spherical quad of its corners); to_cosine a rotation taking the axis to +z, so the
/// core is that cone. Returns false (probe untouched) where no light qualifies or the cone's half-angle is above
/// kContourMaxHalfAngle. `shape` receives the light's shape (its probe rays pass through it).
inline bool light_core(const SilhouetteQuery& q, ContourProbe& probe, int& shape) {
  LightPolygon best;
  bool found = false;
  double best_weight = 0;
  Vec3 best_centre = Vec3::Zero();
  const auto consider = [&](const LightPolygon& l) {
    std::array<Vec3, 4> local;  // the corners relative to p in the shading frame
    if (!light_toward(l, q, local)) return;
    bool above = false;
    for (const Vec3& c : local) above |= c.z() > 0;
    if (!above) return;
    const Vec3 centre = 0.25 * (l.corners[0] + l.corners[1] + l.corners[2] + l.corners[3]);
    const Vec3 d = centre - q.p;
    const double d2 = d.squaredNorm();
    const double cos_light = -l.normal.dot(d) / std::sqrt(d2);
    const double area = 0.5 * ((l.corners[2] - l.corners[0]).cross(l.corners[3] - l.corners[1])).norm();
    const double w = l.weight * area * cos_light / d2;
    if (w > best_weight) {
      best_weight = w;
      best = l;
      best_centre = centre;
      found = true;
    }
  };
  for_each_light_quad(q, consider);
  if (!found) return false;
  const Vec3 axis = (best_centre - q.p).normalized();
  double cos_half = 1;
  for (const Vec3& c : best.corners) cos_half = std::min(cos_half, axis.dot((c - q.p).normalized()));
  if (!(cos_half >= std::cos(kContourMaxHalfAngle))) return false;
  const Vec3 s = axis.unitOrthogonal(), t = axis.cross(s);
  probe.axis = axis;
  probe.cos_half_angle = cos_half;
  probe.to_cosine << s.transpose(), t.transpose(), axis.transpose();
  probe.cos_core = cos_half;
  shape = best.shape;
  return true;
}

}  // namespace qsil::edgetree
