#pragma once
/// @file bsdf.h
/// Evaluation and sampling of the BSDFs of the scene model (qsil::BSDFDesc, scene.h): Lambertian
/// `diffuse` and GGX `roughconductor` with Fresnel factor 1 scaled by `specular_reflectance`,
/// both optionally `twosided` — matching Mitsuba 3's plugins of the same names.
///
/// Frames and directions: every direction is in the LOCAL shading frame (z = shading normal),
/// unit length, pointing AWAY from the surface: wi toward the light, wo toward the viewer.
///
/// Microfacet model (Walter et al. 2007, "Microfacet Models for Refraction through Rough
/// Surfaces", EGSR; Heitz 2014, "Understanding the Masking-Shadowing Function in
/// Microfacet-Based BRDFs", JCGT 3(2)):
///   f_s(wi, wo) = F * D(h) * G(wi, wo, h) / (4 cos_i cos_o),  h = normalize(wi + wo),
///   D = isotropic GGX [Walter Eq. 33], G = G1(wi, h) * G1(wo, h), the *separable* Smith form
///   (Mitsuba 3's MicrofacetDistribution::G, its default), G1 = Smith GGX [Walter Eq. 34].
/// The separable form is not the height-correlated one (Heitz 2014 Eq. 99); it is chosen to match
/// Mitsuba 3 exactly, so reference renders agree.
///
/// Differentiation (docs/architecture.md §4): bsdf_eval and the ggx_* evaluation helpers are templates over
/// the scalar T (double or Eigen::AutoDiffScalar), so BSDF *values* carry derivatives with respect
/// to the (moving) shading frame. Sampling and pdfs are double only: sampled directions and pdfs
/// are detached. Only the support test (which side of the surface) branches.

#include "qsil/math.h"
#include "qsil/scene.h"

#include <algorithm>
#include <cmath>

namespace qsil {

/// Smallest GGX roughness used for evaluation and sampling (Mitsuba 3 clamps alpha to 1e-4 the
/// same way): below it D overflows in double for the mirror direction.
inline constexpr double kMinGGXAlpha = 1e-4;

/// The GGX alpha actually used for BSDF `b`: max(b.alpha, kMinGGXAlpha).
inline double ggx_alpha(const BSDFDesc& b) { return std::max(b.alpha, kMinGGXAlpha); }

// ---------------------------------------------------------------------------------------------
// GGX building blocks (isotropic, local frame). Usable with any alpha (e.g. for the importance of
// edges, docs/architecture.md §5).
// ---------------------------------------------------------------------------------------------

/// GGX normal distribution D(m) for a unit microfacet normal m [Walter 2007 Eq. 33]:
///   D(m) = 1 / (pi alpha^2 (m.z^2 + (m.x^2 + m.y^2)/alpha^2)^2) for m.z > 0, else 0.
/// Normalised so that the projected area integrates to one: integral D(m) m.z dm = 1. Units sr^-1.
template <class T>
T ggx_D(double alpha, const Vec3T<T>& m) {
  if (!(m.z() > 0.0)) return T(0.0);
  const double a2 = alpha * alpha;
  const T s = (m.x() * m.x() + m.y() * m.y()) / a2 + m.z() * m.z();
  return T(1.0) / (T(kPi * a2) * s * s);
}

/// Smith masking G1(v, m) for GGX [Walter 2007 Eq. 34], written without tan to stay finite at
/// grazing angles: G1 = 2 |v.z| / (|v.z| + sqrt(v.z^2 + alpha^2 (v.x^2 + v.y^2))), and 0 when the
/// microfacet's back is seen, i.e. (v.m)(v.z) <= 0 (the chi+ factor). v, m unit. Dimensionless.
template <class T>
T ggx_G1(double alpha, const Vec3T<T>& v, const Vec3T<T>& m) {
  using std::sqrt;
  const T vm = v.dot(m);
  if (!(vm * v.z() > 0.0)) return T(0.0);
  const T c = v.z() < 0.0 ? T(-v.z()) : T(v.z());
  const T xy2 = v.x() * v.x() + v.y() * v.y();
  const T root = sqrt(c * c + T(alpha * alpha) * xy2);
  return T(2.0) * c / (c + root);
}

/// Cosine-weighted GGX reflection with F = 1, for wi, wo both strictly above the surface (z > 0):
///   f_s(wi,wo) cos_i = D(h) G1(wi,h) G1(wo,h) / (4 cos_o),  h = normalize(wi + wo).
/// Returns 0 when either direction is not above the surface. Dimensionless (sr^-1 times sr^0).
template <class T>
T ggx_eval_cos(double alpha, const Vec3T<T>& wi, const Vec3T<T>& wo) {
  using std::sqrt;
  if (!(wi.z() > 0.0) || !(wo.z() > 0.0)) return T(0.0);
  const Vec3T<T> hs = wi + wo;  // |hs| > 0 since both are in the upper hemisphere
  const Vec3T<T> h = hs / T(sqrt(hs.dot(hs)));
  const T d = ggx_D<T>(alpha, h);
  const T g = ggx_G1<T>(alpha, wi, h) * ggx_G1<T>(alpha, wo, h);
  return d * g / (T(4.0) * wo.z());
}

/// Samples a microfacet normal from the distribution of visible normals D_v(m) =
/// G1(v,m) max(0, v.m) D(m) / v.z for a view direction v with v.z > 0 (Heitz 2018, "Sampling the
/// GGX Distribution of Visible Normals", JCGT 7(4), Listing 1). u in [0,1)^2. Returns a unit m
/// with m.z >= 0.
Vec3 ggx_sample_visible_normal(double alpha, const Vec3& v, const Vec2& u);

/// Density D_v(m) of ggx_sample_visible_normal, per unit solid angle of m (0 if v.z <= 0).
double ggx_visible_normal_pdf(double alpha, const Vec3& v, const Vec3& m);

/// Mirror reflection of w about the unit normal m: 2 (w.m) m - w.
inline Vec3 reflect(const Vec3& w, const Vec3& m) { return 2.0 * w.dot(m) * m - w; }

/// Solid-angle density over the WHOLE sphere of wi = reflect(wo, m) with m drawn from
/// ggx_sample_visible_normal(alpha, wo, .), for wo.z > 0:
///   pdf(wi) = D_wo(m) / (4 wo.m) = G1(wo,m) D(m) / (4 wo.z),  m = normalize(wi + wo)
/// (the Jacobian dm/dwi = 1/(4 |wi.m|), Walter 2007 Eq. 14). It integrates to exactly 1 over the
/// sphere; part of it can lie below the horizon (wi.z <= 0), where the sample is discarded.
double ggx_reflection_pdf(double alpha, const Vec3& wi, const Vec3& wo);

// ---------------------------------------------------------------------------------------------
// The BSDF interface used by the integrators
// ---------------------------------------------------------------------------------------------

/// Cosine-weighted BSDF value f_s(wi, wo) |cos theta_i| per RGB channel, in the local shading frame.
/// - Zero when wi and wo lie on opposite sides (reflection only), and for a one-sided BSDF when
///   wo.z <= 0 (Mitsuba 3: the back side is black).
/// - twosided: when wo.z < 0 both directions are mirrored to the upper side (z -> -z) first.
/// - Diffuse: reflectance * cos_i / pi. RoughConductor: specular_reflectance * ggx_eval_cos.
/// Differentiable in wi and wo (T = double or a forward-mode dual number); only the support test
/// branches. The value is reciprocal: bsdf_eval(wi,wo)/|cos_i| = bsdf_eval(wo,wi)/|cos_o|.
template <class T>
ColorT<T> bsdf_eval(const BSDFDesc& b, const Vec3T<T>& wi_in, const Vec3T<T>& wo_in) {
  ColorT<T> out;
  for (int c = 0; c < 3; ++c) out[c] = T(0.0);
  Vec3T<T> wi = wi_in, wo = wo_in;
  if (wo.z() < 0.0) {
    if (!b.twosided) return out;
    wi.z() = -wi.z();
    wo.z() = -wo.z();
  }
  if (!(wo.z() > 0.0) || !(wi.z() > 0.0)) return out;
  T scalar(0.0);
  const Color* tint = nullptr;
  switch (b.type) {
    case BSDFDesc::Type::Diffuse:
      scalar = wi.z() * kInvPi;
      tint = &b.reflectance;
      break;
    case BSDFDesc::Type::RoughConductor:
      scalar = ggx_eval_cos<T>(ggx_alpha(b), wi, wo);
      tint = &b.specular_reflectance;
      break;
  }
  for (int c = 0; c < 3; ++c) out[c] = T((*tint)[c]) * scalar;
  return out;
}

/// A sampled incident direction. wi is in the local frame; pdf is per unit solid angle.
/// valid = false marks a sample that carries no contribution (wi on the wrong side of the
/// surface, or a one-sided BSDF seen from behind); its pdf is still the proposal density when the
/// direction was proposed (see bsdf_pdf), or 0.
struct BSDFSample {
  Vec3 wi = Vec3::Zero();
  double pdf = 0;
  bool valid = false;
};

/// Share of a diffuse BSDF's directions that paths carrying derivatives (the interior term's
/// dual paths in forward and reverse mode, integrators/path_tracer.h) draw uniformly over the
/// hemisphere instead of cosine-weighted: a defensive mixture (Hesterberg 1995, "Weighted average
/// importance sampling and defensive mixture distributions", Technometrics 37(2)). Why: with
/// directions fixed and pdfs detached, a moving shading normal gives the throughput the derivative
/// albedo (dn_s . wi) / cos_i under the cosine density, of diverging variance; the mixture bounds
/// it by 2 pi |dn_s| / share (docs/architecture.md §4 "Sampling for derivatives"; measured:
/// docs/design-notes.md "Sampling for derivatives, measured"). Primal paths (`render`, FD, the
/// boundary term's radiance sub-paths) keep share 0, so `grad`'s primal channels are unbiased but
/// not equal to `render`'s for the same seed.
inline constexpr double kDerivativeDiffuseUniformShare = 0.25;

/// Samples wi given wo (local frame, unit), u in [0,1)^2.
/// - Diffuse: on wo's side, uniform over the hemisphere with probability `uniform_share` (in
///   [0, 1); u.x chooses), else cosine-weighted: pdf = share/(2 pi) + (1 - share) |cos_i|/pi.
/// - RoughConductor: visible-normal sampling of m (Heitz 2018) and wi = reflect(wo, m),
///   pdf = D_wo(m) / (4 |wo.m|) (ggx_reflection_pdf). A wi that lands on the other side of the
///   surface than wo is returned with valid = false.
/// twosided: mirrored when wo.z < 0; one-sided with wo.z <= 0: invalid, pdf = 0.
BSDFSample bsdf_sample(const BSDFDesc& b, const Vec3& wo, const Vec2& u, double uniform_share = 0.0);

/// Solid-angle density with which bsdf_sample(b, wo, .) proposes wi, over the whole sphere
/// (including directions that bsdf_sample flags invalid, so it integrates to 1 for any wo the
/// BSDF can be seen from, and to 0 for a one-sided BSDF seen from behind). Wherever bsdf_eval is
/// non-zero this equals the density of valid samples, which is what MIS needs. `uniform_share`
/// as for bsdf_sample (diffuse only).
double bsdf_pdf(const BSDFDesc& b, const Vec3& wi, const Vec3& wo, double uniform_share = 0.0);

}  // namespace qsil
