/// @file edge_mixture.cpp
/// See edge_mixture.h.

#include "edge_mixture.h"

#include "positive_part.h"

#include <algorithm>
#include <cmath>

namespace qsil::edgetree {

namespace {

const EdgePointSampler kEmpty(Vec3::Zero(), Vec3::Zero(), LTC{});

/// The interval [lo, hi] of t where w0 + t (w1 − w0) lies inside the pyramid from the origin over
/// a light with inward side normals `sides` (w0, w1 relative to p, in the sides' frame); hi < lo
/// when the segment misses it.
void pyramid_interval(const std::array<Vec3, 4>& sides, const Vec3& w0, const Vec3& w1, double& lo, double& hi) {
  lo = 0.0;
  hi = 1.0;
  for (int i = 0; i < 4 && hi >= lo; ++i) {
    const Vec3& n = sides[size_t(i)];
    const double a = n.dot(w0), b = n.dot(w1);  // n . w(t) >= 0 on the light's side
    if (a >= 0 && b >= 0) continue;
    if (a < 0 && b < 0) {
      hi = -1.0;
      return;
    }
    const double tc = a / (a - b);
    if (a >= 0)
      hi = std::min(hi, tc);
    else
      lo = std::max(lo, tc);
  }
}

/// W_i of a component: its radiance times its LTC integral, 0 unless finite and positive.
double component_weight(double radiance, double integral) {
  const double w = radiance * integral;
  return std::isfinite(w) && w > 0 ? w : 0.0;
}

/// Calls component(lo, hi, radiance) for each of the mixture's components of edge e (endpoints
/// w0, w1 relative to p, in the local frame, or in the world frame when `world`), in order: the
/// whole edge with the environment's radiance (plus e's emission), then the part in front of each
/// of the first kMaxLights lights that the edge crosses, with that light's.
template <bool world = false, class Component>
void for_each_component(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights,
                        const Vec3& w0, const Vec3& w1, Component&& component) {
  double base = q.env_weight;
  if (q.emission && e.shape >= 0 && e.shape < int(q.emission->size())) base += (*q.emission)[size_t(e.shape)];
  component(0.0, 1.0, base);  // also the angle-uniform part (comp_[0])
  int used = 0;
  for (const LocalLight& light : lights) {
    if (used == EdgeMixture::kMaxLights) break;
    double lo, hi;
    pyramid_interval(world ? light.sides_world : light.sides, w0, w1, lo, hi);
    if (!(hi > lo)) continue;
    component(lo, hi, light.weight);
    ++used;
  }
}

}  // namespace

EdgeMixture::EdgeMixture(const Edge& e, const SilhouetteQuery& q) : EdgeMixture(e, q, [&] {
  std::vector<LocalLight> lights;
  local_lights(q, lights);
  return lights;
}()) {}

EdgeMixture::EdgeMixture(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights)
    : comp_{kEmpty, kEmpty, kEmpty, kEmpty, kEmpty} {
  const Vec3 w0 = q.frame.to_local(e.p0 - q.p), w1 = q.frame.to_local(e.p1 - q.p);
  for_each_component(e, q, lights, w0, w1, [&](double lo, double hi, double radiance) {
    comp_[size_t(n_)] = EdgePointSampler(w0, w1, q.ltc, kEdgeDefensiveShare, lo, hi);
    weight_[size_t(n_)] = component_weight(radiance, comp_[size_t(n_)].target_integral());
    total_ += weight_[size_t(n_)];
    ++n_;
  });
  eps_ = total_ > 0 ? kEdgeDefensiveShare : 1.0;
}

LtcMap::LtcMap(const SilhouetteQuery& q) : normal(q.frame.n), scale(q.ltc.norm * std::abs(q.ltc.det_M_inv) * kInvPi) {
  Mat3 to_local;
  to_local.row(0) = q.frame.s.transpose();
  to_local.row(1) = q.frame.t.transpose();
  to_local.row(2) = q.frame.n.transpose();
  to_cosine = q.ltc.M_inv * to_local;
}

double EdgeMixture::total(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights) {
  return total(e, q, lights, LtcMap(q), EdgeGeometry(e, q.p));
}

double EdgeMixture::total(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights,
                          const LtcMap& map, const EdgeGeometry& g) {
  const Vec3 u0 = map.to_cosine * g.w0, u1 = map.to_cosine * g.w1;
  const double z0 = map.normal.dot(g.w0), z1 = map.normal.dot(g.w1);
  double total = 0;
  for_each_component<true>(e, q, lights, g.w0, g.w1, [&](double lo, double hi, double radiance) {
    total += component_weight(radiance,
                              EdgePointSampler::ltc_integral_mapped(u0, u1, z0, z1, g.normal_len, map.scale, lo, hi));
  });
  return total;
}

namespace {

/// The integral over t in [lo, hi] of max(0, a + t (b - a)).
double positive_part_integral(double a, double b, double lo, double hi) {
  lo = std::max(lo, 0.0);
  hi = std::min(hi, 1.0);
  if (!(hi > lo)) return 0.0;
  const double fa = a + lo * (b - a), fb = a + hi * (b - a);
  return mean_positive_part(std::min(fa, fb), std::max(fa, fb)) * (hi - lo);
}

}  // namespace

double EdgeMixture::far_total(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights) {
  return far_total(e, q, lights, EdgeGeometry(e, q.p));
}

double EdgeMixture::far_total(const Edge& e, const SilhouetteQuery& q, std::span<const LocalLight> lights,
                              const EdgeGeometry& g) {
  const double d2 = g.mid2;
  if (!(d2 > 0)) return 0.0;
  // g(t) = |w0 x w1| / |w_t|^4 * norm * max(0, w_t.z) / pi with |w_t| = d; in the world frame
  // (the lights' side normals too), w.z = n . w with n the shading normal.
  const double scale = g.normal_len / (d2 * d2) * q.ltc.norm / kPi;
  const double z0 = q.frame.n.dot(g.w0), z1 = q.frame.n.dot(g.w1);
  double total = 0;
  for_each_component<true>(e, q, lights, g.w0, g.w1, [&](double lo, double hi, double radiance) {
    total += component_weight(radiance, scale * positive_part_integral(z0, z1, lo, hi));
  });
  return total;
}

EdgePointSample EdgeMixture::sample(double u) const {
  u = std::clamp(u, 0.0, 1.0);
  double t;
  if (u < 1.0 - eps_) {
    // Choose a component in proportion to W_i, then reuse what is left of u within it.
    double v = u / (1.0 - eps_) * total_;
    int pick = -1;
    for (int i = 0; i < n_; ++i) {
      if (!(weight_[size_t(i)] > 0)) continue;
      pick = i;  // the last positive component takes what rounding leaves over
      if (v < weight_[size_t(i)]) break;
      v -= weight_[size_t(i)];
    }
    t = comp_[size_t(pick)].sample_ltc(std::clamp(v / weight_[size_t(pick)], 0.0, std::nextafter(1.0, 0.0)));
  } else {
    const double v = (u - (1.0 - eps_)) / eps_;
    t = comp_[0].sample_angle(std::min(v, std::nextafter(1.0, 0.0)));
  }
  return {t, pdf(t)};
}

double EdgeMixture::pdf(double t) const {
  if (!(t >= 0.0 && t <= 1.0)) return 0.0;
  double p = eps_ * comp_[0].angle_pdf(t);
  if (eps_ < 1.0)
    for (int i = 0; i < n_; ++i)
      if (weight_[size_t(i)] > 0) p += (1.0 - eps_) * weight_[size_t(i)] / total_ * comp_[size_t(i)].ltc_pdf(t);
  return p;
}

}  // namespace qsil::edgetree
