#pragma once
/// @file edge_point_sampler.h
/// Sampling the point on a chosen edge (docs/architecture.md §5 "Point on the edge").
///
/// Setting: a shading point p, its local shading frame (z = shading normal), an edge with
/// endpoints x0, x1 given relative to p in that frame: w0 = x0 - p, w1 = x1 - p (scene units),
/// w_t = w0 + t (w1 - w0), t in [0, 1], omega(t) = w_t / |w_t|. The target is the integrand of
/// [QSS] Eq. 4 weighted by the cosine-weighted BSDF through its LTC (ltc.h):
///   g(t) = |w0 x w1| / |w_t|^3 * norm * D(omega(t))
/// (|w0 x w1| / |w_t|^2 dt is the subtended-angle element, so g = BSDF x angle / distance).
///
/// Density: p(t) = (1 - eps) g(t) / integral(g) + eps * p_angle(t), with the defensive share
/// eps (default 0.15) uniform in subtended angle over the WHOLE edge,
///   p_angle(t) = |w0 x w1| / (|w_t|^2 Phi),  Phi = angle(w0, w1),
/// so p(t) > 0 for every t in [0, 1], including parts of the edge below the shading horizon or
/// outside the LTC's support, where the true integrand (e.g. for another BSDF lobe, or the
/// LTC's approximation error) may still be non-zero (docs/architecture.md §5 pitfalls). eps = 1 when the
/// LTC part vanishes on the whole edge (integral(g) = 0). When p lies on the edge's line
/// (|w0 x w1| = 0, Phi = 0) the density is uniform in t (p(t) = 1); the integrand is 0 there anyway.
///
/// Method (closed-form CDF; the returned pdf is the exact density of the procedure): mapped by
/// the LTC to u_t = M^-1 w_t, g dt is a product of two sinusoids in the angle psi subtended in
/// that space, over the interval [t_a, t_b] where w_t.z > 0 and u_t.z > 0; F(psi) = u F(Psi) is
/// solved by Newton's method safeguarded by bisection, t follows from psi in closed form, and the
/// angle-uniform part inverts exactly (derivation: docs/experiments/2026-11-25-header-notes.md,
/// "edge_point_sampler.h: the method"). Why not a tabulated CDF: exact for any roughness (alpha =
/// 1e-4 lobes are far narrower than any fixed table over t) for a few Newton steps. Sources:
/// [QSS] Eq. 4; Heitz et al. 2016 (LTC); the structure of Li et al. 2018 / Peters 2021's LTC line
/// integrals (derived here independently).
///
/// Units: t is dimensionless, pdf(t) per unit t, target(t) and target_integral() per scene unit.

#include "qsil/edgetree/ltc.h"
#include "qsil/math.h"

namespace qsil::edgetree {

/// A sampled edge parameter t in [0, 1] and its density per unit t (> 0).
struct EdgePointSample {
  double t = 0;
  double pdf = 0;
};

/// Default defensive share (fraction of samples uniform in subtended angle).
inline constexpr double kEdgeDefensiveShare = 0.15;

/// Samples t on one edge for one shading point (see the file comment). Construction precomputes
/// the CDF constants (a few dozen flops); sample() and pdf() are const and thread-safe.
class EdgePointSampler {
 public:
  /// w0, w1: endpoints relative to the shading point, local shading frame, scene units.
  /// ltc: the BSDF's LTC in the same frame (ltc_ggx or ltc_diffuse; a zero norm disables the LTC
  /// part). defensive: the share eps in (0, 1] (clamped to [1e-3, 1]). [t_lo, t_hi]: the part of
  /// the edge the LTC part covers (e.g. the part in front of a light; default the whole edge); the
  /// angle-uniform part always covers [0, 1].
  EdgePointSampler(const Vec3& w0, const Vec3& w1, const LTC& ltc, double defensive = kEdgeDefensiveShare,
                   double t_lo = 0.0, double t_hi = 1.0);

  /// One sample from a uniform number u in [0, 1).
  EdgePointSample sample(double u) const;

  /// The density of sample() at t (per unit t); > 0 on [0, 1] and 0 outside.
  double pdf(double t) const;

  /// The target g(t) = |w0 x w1| / |w_t|^3 * norm * D(omega(t)) (per scene unit; D from
  /// ltc_eval, so 0 below the horizon and outside the LTC support).
  double target(double t) const;

  /// Integral of target(t) over [0, 1] in closed form (per scene unit): the LTC estimate of the
  /// edge's term in [QSS] Eq. 4 (with f_s cos). Usable as a per-edge importance in leaves
  /// (mixed with a defensive term, docs/architecture.md §5).
  double target_integral() const { return target_integral_; }

  /// target_integral() of EdgePointSampler(w0, w1, ltc, ·, t_lo, t_hi) without building the
  /// sampler, from what an edge's importance has at hand per query and per edge: the endpoints
  /// mapped to the LTC's cosine domain (u0 = M_inv w0, u1 = M_inv w1), their heights above the
  /// shading horizon (z0 = w0.z, z1 = w1.z), cross01 = |w0 x w1| and scale = norm |det M_inv| /
  /// pi. The same closed form with only the constants the integral needs (no sampler state, no
  /// LTC copy, 4 square roots instead of 6); equal to target_integral() up to rounding, and zero
  /// where it is zero up to rounding at the ends of an interval (tests/edgetree/edge_mixture_test.cpp).
  static double ltc_integral_mapped(const Vec3& u0, const Vec3& u1, double z0, double z1, double cross01, double scale,
                                    double t_lo = 0.0, double t_hi = 1.0);

  /// The defensive share actually used (1 when the LTC part vanishes).
  double defensive_share() const { return eps_; }

  /// The LTC part alone (for mixtures of several samplers of one edge): its normalised density
  /// at t (0 outside [t_lo, t_hi] and everywhere when target_integral() == 0), and its sample
  /// from u in [0, 1) (only when target_integral() > 0).
  double ltc_pdf(double t) const;
  double sample_ltc(double u) const;
  /// The angle-uniform part alone: its density at t in [0, 1] and its sample from u in [0, 1).
  double angle_pdf(double t) const;
  double sample_angle(double u) const;

 private:
  /// Fills the LTC part (ta_ .. target_integral_) for the interval [t_lo, t_hi]; cross01 = |w0 x w1|.
  /// Leaves target_integral_ = 0 when the LTC part vanishes.
  void setup_ltc(double cross01, double t_lo, double t_hi);

  Vec3 w0_, w1_;
  LTC ltc_;
  double eps_ = 1.0;
  // Angle-uniform part.
  double cross01_ = 0;  ///< |w0 x w1|
  double phi_ = 0;      ///< subtended angle
  double l0_ = 0, l1_ = 0;
  // LTC part: interval, transformed endpoints and the closed-form CDF constants.
  double ta_ = 0, tb_ = 0;
  Vec3 u0_, u1_;                              ///< M_inv w0, M_inv w1
  double la_ = 0, lb_ = 0;                    ///< |u(ta)|, |u(tb)|
  double psi_max_ = 0;                        ///< angle between u(ta) and u(tb)
  double z1_ = 0, z2_ = 0, m1_ = 0, m2_ = 0;  ///< omega'.z and m in the (e1, e2) basis
  double F_total_ = 0;                        ///< F(psi_max)
  double ltc_scale_ = 0;                      ///< |u0 x u1| h / F_total: ltc_pdf(t) = ltc_scale_ * u.z / |u|^4
  double target_integral_ = 0;
};

}  // namespace qsil::edgetree
