#pragma once
/// @file contour_probe.h
/// Where a shading point looks for its contour set (qsil/edgetree/contour_set.h): the rays of the
/// contour probe, traced from the shading point into its BSDF lobe's core or a small light's cone.

#include "qsil/edgetree/contour_set.h"
#include "qsil/edgetree/light_core.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/integrators/surface_interaction.h"

#include <cmath>

namespace qsil {

/// The contour probe of a boundary query (qsil/edgetree/contour_set.h). Its core: where q's LTC is
/// glossy and the cone that bounds its core (ltc_core_cone with kContourConeMass) has a half-angle
/// of at most kContourMaxHalfAngle, the lobe's core in world coordinates; elsewhere (a cosine or
/// wide lobe) the cone of a small light (light_core: a quad, or a light sphere's quad). The probe is made where that cone meets
/// an eligible shape's bounding sphere (ContourIndex::cone_meets_shapes): the first hit of the ray
/// from the shading point along the cone's axis, kept when it is on an eligible shape other than
/// the probed light (a ray that reaches the light met nothing in front of it); where it is not (a
/// miss, the light, or a static shape in front), the first hits of kContourRingRays rays around
/// the axis, at kContourRingAngle times the core's extent (a ring in the core's cosine domain
/// mapped back, so it stays inside a stretched core), those kept by the same rule. Each ray passes
/// through back faces where its direction leaves below the surface, as every ray of the path
/// tracer does. `rays` receives the number of rays traced. A probe with no hit (count 0) gives no
/// contour set.
template <class T>
edgetree::ContourProbe contour_probe(const PathContext& ctx, const edgetree::ContourIndex& contours,
                                     const SurfaceInteraction<T>& si, const Vec3& wo_world,
                                     const edgetree::SilhouetteQuery& q, int& rays) {
  rays = 0;
  edgetree::ContourProbe probe;
  Mat3 M = Mat3::Identity();  // the lobe's LTC matrix (M_inv^-1): its cosine domain back to local directions
  int light = -1;             // the probed light's shape: its hits are misses
  bool lobe = false;
  if (!edgetree::is_cosine_lobe(q.ltc) && q.ltc.norm > 0) {
    const edgetree::LTCCone cone = edgetree::ltc_core_cone(q.ltc, edgetree::kContourConeMass);
    if (cone.cos_half_angle >= std::cos(edgetree::kContourMaxHalfAngle)) {
      lobe = true;
      probe.axis = q.frame.to_world(cone.axis).normalized();
      probe.cos_half_angle = cone.cos_half_angle;
      Mat3 to_local;
      to_local << q.frame.s.transpose(), q.frame.t.transpose(), q.frame.n.transpose();
      probe.to_cosine = q.ltc.M_inv * to_local;
      probe.cos_core = std::sqrt(1.0 - edgetree::kContourConeMass);
      M = q.ltc.M_inv.inverse();
    }
  }
  if (!lobe && !edgetree::light_core(q, probe, light)) return probe;
  if (!contours.cone_meets_shapes(q.p, probe.axis, probe.cos_half_angle, q.eligible)) return probe;
  auto trace = [&](const Vec3& dir) {
    IgnoreSet ignore;
    ignore.through_back_faces = leaves_below(si, wo_world, dir);
    const Vec3 origin = spawn_origin(si, dir);
    ++rays;
    const Hit h = ctx.tracer->intersect(origin, dir, kInf, ignore);
    if (!h.valid() || h.shape == light || !q.is_eligible(h.shape)) return;
    probe.hits[size_t(probe.count++)] = {h.shape, h.triangle, Vec3(origin + h.t * dir), dir};
  };
  trace(probe.axis);
  if (probe.count == 0) {
    // The ring: directions (k tan(gamma) cos(phi), k tan(gamma) sin(phi), 1) of the cosine domain,
    // gamma the core's half-angle there (a lobe's: sin^2 gamma = kContourConeMass; a light's: cos
    // gamma = cos_core).
    const double tan_core = lobe ? std::sqrt(edgetree::kContourConeMass / (1.0 - edgetree::kContourConeMass))
                                 : std::sqrt(std::max(0.0, 1.0 - probe.cos_core * probe.cos_core)) / probe.cos_core;
    const double r = edgetree::kContourRingAngle * tan_core;
    for (int k = 0; k < edgetree::kContourRingRays; ++k) {
      const Vec3 c(r * edgetree::kContourRingCos[k], r * edgetree::kContourRingSin[k], 1.0);
      // A lobe's ring through its LTC to the local frame; a light's through the core's rotation.
      const Vec3 d = lobe ? Vec3(M * c) : Vec3(probe.to_cosine.transpose() * c);
      if (d.allFinite() && d.squaredNorm() > 0) trace(lobe ? q.frame.to_world(d.normalized()) : Vec3(d.normalized()));
    }
  }
  return probe;
}

}  // namespace qsil
