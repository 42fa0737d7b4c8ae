#pragma once
/// @file importance_cases.h
/// Random shading points, lights and placements for the importance tests
/// (edgetree/node_importance_test.cpp, edgetree/edge_importance_test.cpp): a point at the origin
/// with a random normal, 0-2 quad lights around it and a constant environment or none; and
/// directions for the primitive whose importance is judged, placed across a light's outline,
/// across the shading horizon or at random.

#include "chi2.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "ray_hits.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace qsil::test {

/// A direction uniform on the unit sphere.
inline Vec3 random_unit(TestRng& rng) {
  const double z = 2.0 * rng.uniform() - 1.0, phi = 2.0 * kPi * rng.uniform();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Fills q (p at the origin, a random shading frame, the clamped cosine or, with `glossy`, qsil's
/// GGX LTC for alpha log-uniform in [0.01, 0.5] and a random view direction above the horizon;
/// norm in [0.3, 1]; env_weight 0 or in [0.1, 1.1]) and `lights` (0-2 quads 2-6 units away,
/// mostly above the horizon, radiance in [1, 50]); q.lights points to `lights`.
inline void random_query(TestRng& rng, bool glossy, edgetree::SilhouetteQuery& q,
                         std::vector<edgetree::LightPolygon>& lights) {
  const Vec3 n = random_unit(rng);
  q.p = Vec3::Zero();
  q.frame = Frame(n);
  q.ltc = edgetree::ltc_diffuse();
  if (glossy) {
    const double alpha = 0.01 * std::pow(50.0, rng.uniform());
    Vec3 wo = random_unit(rng);
    wo.z() = 0.05 + 0.95 * std::abs(wo.z());
    q.ltc = edgetree::ltc_ggx(alpha, wo);
  }
  q.ltc.norm = 0.3 + 0.7 * rng.uniform();
  q.env_weight = rng.uniform() < 0.5 ? 0.0 : 0.1 + rng.uniform();
  const int n_lights = int(rng.uniform() * 3.0);
  for (int i = 0; i < n_lights; ++i) {
    Vec3 dir = random_unit(rng);
    if (dir.dot(n) < -0.2) dir = -dir;
    const Vec3 c = (2.0 + 4.0 * rng.uniform()) * dir;
    const Vec3 normal = (-dir + 0.6 * random_unit(rng)).normalized();
    const Frame lf(normal);
    const double a = 0.2 + 1.3 * rng.uniform(), b = 0.2 + 1.3 * rng.uniform();
    edgetree::LightPolygon l;
    l.corners = {c - a * lf.s - b * lf.t, c + a * lf.s - b * lf.t, c + a * lf.s + b * lf.t, c - a * lf.s + b * lf.t};
    l.normal = normal;
    l.weight = 1.0 + 49.0 * rng.uniform();
    lights.push_back(l);
  }
  q.lights = &lights;
}

/// Whether the direction w from p (at the origin) meets light l's quad from its emitting side:
/// where the oracles add the light's radiance (the library's light_toward keeps only lights
/// that face p).
inline bool sees_emitting_side(const edgetree::LightPolygon& l, const Vec3& w) {
  return l.normal.dot(-l.corners[0]) > 0 && ray_hits_quad(w, l.corners);
}

/// A unit direction from p for a primitive of angular radius about asin(s): with probability
/// 0.35 through a random point of a light's outline (when there is a light), 0.35 within s of
/// the horizon of q's frame, else uniform. `straddle` says whether it was one of the first two.
inline Vec3 random_placement(TestRng& rng, const edgetree::SilhouetteQuery& q,
                             const std::vector<edgetree::LightPolygon>& lights, double s, bool& straddle) {
  const double placement = rng.uniform();
  straddle = placement < 0.7;
  if (placement < 0.35 && !lights.empty()) {  // across a light's outline
    const edgetree::LightPolygon& l = lights[size_t(rng.uniform() * double(lights.size()))];
    const int i = int(rng.uniform() * 4.0);
    const double t = rng.uniform();
    return ((1 - t) * l.corners[size_t(i)] + t * l.corners[size_t((i + 1) % 4)]).normalized();
  }
  if (placement < 0.7) {  // across the horizon
    const double phi = 2.0 * kPi * rng.uniform(), z = s * (2.0 * rng.uniform() - 1.0);
    return q.frame.to_world(Vec3(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z));
  }
  return random_unit(rng);
}

/// The u-quantile (u in [0, 1]) of values sorted ascending (non-empty): the element at rank
/// floor(u (n - 1)).
inline double quantile(const std::vector<double>& sorted, double u) {
  return sorted[size_t(u * double(sorted.size() - 1))];
}

}  // namespace qsil::test
