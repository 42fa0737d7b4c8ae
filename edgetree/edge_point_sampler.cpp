/// @file edge_point_sampler.cpp
/// Closed-form CDF sampling of a point on an edge under the LTC-weighted [QSS] Eq. 4 integrand,
/// with a defensive angle-uniform share (see edge_point_sampler.h).

#include "edge_point_sampler.h"

#include <algorithm>
#include <cmath>

namespace qsil::edgetree {
namespace {

/// psi/2 - sin(2 psi)/4 = integral of sin^2 from 0 to psi; a series below 1e-2 avoids the
/// cancellation (relative error about 1e-15 there: the next term is -psi^9 / 2835).
double int_sin2(double psi) {
  if (std::abs(psi) < 1e-2) {
    const double p2 = psi * psi;
    return psi * p2 * (1.0 / 3.0 - p2 * (1.0 / 15.0 - p2 * (2.0 / 315.0)));
  }
  return 0.5 * psi - 0.25 * std::sin(2.0 * psi);
}

/// psi/2 + sin(2 psi)/4 = integral of cos^2 from 0 to psi, and int_sin2, given s = sin(psi) and
/// c = cos(psi) (sin 2 psi = 2 s c): no trigonometric call where the caller has them (setup_ltc,
/// from the cross and dot products psi came from; sample_ltc, one sine and cosine per step).
double int_cos2(double psi, double s, double c) { return 0.5 * (psi + s * c); }
double int_sin2(double psi, double s, double c) {
  if (std::abs(psi) < 1e-2) return int_sin2(psi);
  return 0.5 * (psi - s * c);
}

/// Interval of t in [0, 1] where the linear function a + t (b - a) is > 0, intersected with
/// [lo, hi] in place.
void restrict_positive(double a, double b, double& lo, double& hi) {
  if (a > 0.0 && b > 0.0) return;
  if (!(a > 0.0) && !(b > 0.0)) {
    hi = lo - 1.0;  // empty
    return;
  }
  const double tc = a / (a - b);
  if (a > 0.0)
    hi = std::min(hi, tc);
  else
    lo = std::max(lo, tc);
}

/// Parameter s in [0, 1] of the point of segment A -> B (|A| = la, |B| = lb, angle Psi between
/// them) seen at angle psi from A: s = la sin psi / (la sin psi + lb sin(Psi - psi)); both terms
/// are >= 0 for psi in [0, Psi], Psi < pi.
double segment_param(double la, double lb, double Psi, double psi) {
  const double a = la * std::sin(psi), b = lb * std::sin(Psi - psi);
  const double den = a + b;
  if (!(den > 0.0)) return psi > 0.5 * Psi ? 1.0 : 0.0;
  return std::clamp(a / den, 0.0, 1.0);
}

}  // namespace

EdgePointSampler::EdgePointSampler(const Vec3& w0, const Vec3& w1, const LTC& ltc, double defensive, double t_lo,
                                   double t_hi)
    : w0_(w0), w1_(w1), ltc_(ltc) {
  cross01_ = w0.cross(w1).norm();
  phi_ = std::atan2(cross01_, w0.dot(w1));
  l0_ = w0.norm();
  l1_ = w1.norm();
  eps_ = 1.0;
  setup_ltc(cross01_, t_lo, t_hi);
  if (target_integral_ > 0.0) eps_ = std::clamp(defensive, 1e-3, 1.0);
}

double EdgePointSampler::ltc_integral_mapped(const Vec3& u0, const Vec3& u1, double z0, double z1, double cross01,
                                             double scale, double t_lo, double t_hi) {
  if (!(scale > 0.0) || !(cross01 > 0.0) || !std::isfinite(cross01)) return 0.0;
  double lo = std::max(0.0, t_lo), hi = std::min(1.0, t_hi);
  restrict_positive(z0, z1, lo, hi);
  restrict_positive(u0.z(), u1.z(), lo, hi);
  if (!(hi > lo)) return 0.0;
  // setup_ltc's quantities, with its unit vectors folded into dot products: e1 = ua / la,
  // n = cu / cun, e2 = n x e1, m = (d x n) / |d| (the unit normal of the edge's line toward it,
  // m . ua = h), so z1 = ua.z / la, z2 = (cu x ua).z / (cun la), m1 = h / la,
  // m2 = -(d . ua) / (la |d|), and |u0 x u1| = cun / (hi - lo).
  const Vec3 du = u1 - u0;
  const Vec3 ua = u0 + lo * du, ub = u0 + hi * du;
  const double la = ua.norm(), lb = ub.norm();
  const Vec3 cu = ua.cross(ub);
  const double cun = cu.norm(), dot_ab = ua.dot(ub);
  const double psi_max = std::atan2(cun, dot_ab);
  if (!(cun > 0.0) || !(psi_max > 0.0) || !(la > 0.0)) return 0.0;
  const Vec3 d = ub - ua;
  const double dn = d.norm();
  const double h = cun / dn;
  const double zz1 = ua.z() / la, zz2 = cu.cross(ua).z() / (cun * la);
  const double mm1 = h / la, mm2 = -d.dot(ua) / (la * dn);
  const double lab = la * lb;
  const double sp = cun / lab, cp = dot_ab / lab;
  const double F = zz1 * mm1 * int_cos2(psi_max, sp, cp) + (zz1 * mm2 + zz2 * mm1) * 0.5 * sp * sp +
                   zz2 * mm2 * int_sin2(psi_max, sp, cp);
  if (!(F > 0.0) || !std::isfinite(F)) return 0.0;
  // target_integral = norm |w0 x w1| |det| / pi / (|u0 x u1| h) F, |u0 x u1| h = cun^2 / ((hi - lo) dn).
  const double integral = scale * cross01 * (hi - lo) * dn / (cun * cun) * F;
  return std::isfinite(integral) && integral > 0.0 ? integral : 0.0;
}

void EdgePointSampler::setup_ltc(double cross01, double t_lo, double t_hi) {
  const Vec3 &w0 = w0_, &w1 = w1_;
  const LTC& ltc = ltc_;
  if (!(ltc.norm > 0.0) || !(cross01 > 0.0) || !std::isfinite(cross01)) return;

  u0_ = ltc.M_inv * w0;
  u1_ = ltc.M_inv * w1;
  double lo = std::max(0.0, t_lo), hi = std::min(1.0, t_hi);
  restrict_positive(w0.z(), w1.z(), lo, hi);
  restrict_positive(u0_.z(), u1_.z(), lo, hi);
  if (!(hi > lo)) return;
  ta_ = lo;
  tb_ = hi;
  const Vec3 ua = u0_ + ta_ * (u1_ - u0_);
  const Vec3 ub = u0_ + tb_ * (u1_ - u0_);
  la_ = ua.norm();
  lb_ = ub.norm();
  const Vec3 cu = ua.cross(ub);
  const double cun = cu.norm();
  const double dot_ab = ua.dot(ub);
  psi_max_ = std::atan2(cun, dot_ab);
  if (!(cun > 0.0) || !(psi_max_ > 0.0) || !(la_ > 0.0)) return;
  const Vec3 e1 = ua / la_;
  const Vec3 n = cu / cun;
  const Vec3 e2 = n.cross(e1);
  const Vec3 d = ub - ua;
  const double dn = d.norm();
  const double h = cun / dn;  // distance from the origin to the transformed edge's line
  Vec3 m = n.cross(d) / dn;
  if (m.dot(ua) < 0.0) m = -m;
  z1_ = e1.z();
  z2_ = e2.z();
  m1_ = m.dot(e1);
  m2_ = m.dot(e2);
  // sin and cos of psi_max from the cross and dot products it came from (no trigonometric call).
  const double lab = la_ * lb_;
  const double sp = cun / lab, cp = dot_ab / lab;
  F_total_ = z1_ * m1_ * int_cos2(psi_max_, sp, cp) + (z1_ * m2_ + z2_ * m1_) * 0.5 * sp * sp +
             z2_ * m2_ * int_sin2(psi_max_, sp, cp);
  if (!(F_total_ > 0.0) || !std::isfinite(F_total_)) return;
  const double cross_u01 = u0_.cross(u1_).norm();  // = |ua x ub| / (tb - ta)
  if (!(cross_u01 > 0.0)) return;
  ltc_scale_ = cross_u01 * h / F_total_;
  // integral g dt = norm * |w0 x w1| det / pi / (|u0 x u1| h) * F_total.
  target_integral_ = ltc.norm * cross01 * std::abs(ltc.det_M_inv) * kInvPi / (cross_u01 * h) * F_total_;
  if (!(target_integral_ > 0.0) || !std::isfinite(target_integral_) || !std::isfinite(ltc_scale_)) {
    target_integral_ = 0.0;
    ltc_scale_ = 0.0;
  }
}

double EdgePointSampler::ltc_pdf(double t) const {
  if (!(ltc_scale_ > 0.0) || !(t >= ta_ && t <= tb_)) return 0.0;
  const Vec3 w = w0_ + t * (w1_ - w0_);
  if (!(w.z() > 0.0)) return 0.0;
  const Vec3 u = u0_ + t * (u1_ - u0_);
  if (!(u.z() > 0.0)) return 0.0;
  const double l2 = u.squaredNorm();
  return ltc_scale_ * u.z() / (l2 * l2);
}

double EdgePointSampler::angle_pdf(double t) const {
  if (!(cross01_ > 0.0) || !(phi_ > 0.0)) return 1.0;
  const Vec3 w = w0_ + t * (w1_ - w0_);
  return cross01_ / (w.squaredNorm() * phi_);
}

double EdgePointSampler::pdf(double t) const {
  if (!(t >= 0.0 && t <= 1.0)) return 0.0;
  const double pl = eps_ < 1.0 ? (1.0 - eps_) * ltc_pdf(t) : 0.0;
  return pl + eps_ * angle_pdf(t);
}

double EdgePointSampler::target(double t) const {
  const Vec3 w = w0_ + t * (w1_ - w0_);
  const double l = w.norm();
  if (!(l > 0.0)) return 0.0;
  return cross01_ / (l * l * l) * ltc_.norm * ltc_eval(ltc_, w);
}

double EdgePointSampler::sample_angle(double u) const {
  if (!(cross01_ > 0.0) || !(phi_ > 0.0)) return std::clamp(u, 0.0, 1.0);
  return segment_param(l0_, l1_, phi_, u * phi_);
}

double EdgePointSampler::sample_ltc(double u) const {
  const double target = u * F_total_;
  // F (the CDF up to F_total) and its derivative f at p, from one sine and cosine of p.
  auto F = [&](double p, double s, double c) {
    return z1_ * m1_ * int_cos2(p, s, c) + (z1_ * m2_ + z2_ * m1_) * 0.5 * s * s + z2_ * m2_ * int_sin2(p, s, c);
  };
  auto f = [&](double s, double c) { return (z1_ * c + z2_ * s) * (m1_ * c + m2_ * s); };
  double lo = 0.0, hi = psi_max_;
  double psi = u * psi_max_;
  for (int it = 0; it < 100; ++it) {
    const double sn = std::sin(psi), cs = std::cos(psi);
    const double val = F(psi, sn, cs) - target;
    if (val > 0.0)
      hi = psi;
    else
      lo = psi;
    if (std::abs(val) <= 1e-15 * F_total_ || hi - lo <= 1e-15 * psi_max_) break;
    const double d = f(sn, cs);
    double next = psi - val / d;
    if (!(d > 0.0) || !(next > lo && next < hi)) next = 0.5 * (lo + hi);
    psi = next;
  }
  const double s = segment_param(la_, lb_, psi_max_, psi);
  return std::clamp(ta_ + s * (tb_ - ta_), ta_, tb_);
}

EdgePointSample EdgePointSampler::sample(double u) const {
  u = std::clamp(u, 0.0, 1.0);
  double t;
  if (u < 1.0 - eps_) {
    t = sample_ltc(u / (1.0 - eps_));
  } else {
    const double v = eps_ > 0.0 ? (u - (1.0 - eps_)) / eps_ : 0.0;
    t = sample_angle(std::min(v, 1.0));
  }
  return {t, pdf(t)};
}

}  // namespace qsil::edgetree
