/// @file bsdf.cpp
/// BSDF sampling and pdfs (double only; see include/qsil/bsdf.h for the model and conventions).

#include "qsil/bsdf.h"

#include "qsil/check.h"
#include "qsil/sampling.h"

#include <cmath>

namespace qsil {

Vec3 ggx_sample_visible_normal(double alpha, const Vec3& v, const Vec2& u) {
  // Heitz 2018, Listing 1 (isotropic: alpha_x = alpha_y = alpha).
  // Stretch the view direction to the hemisphere configuration (alpha = 1).
  const Vec3 vh = Vec3(alpha * v.x(), alpha * v.y(), v.z()).normalized();
  // Orthonormal basis around vh (T1 is undefined at normal incidence: use x).
  const double lensq = vh.x() * vh.x() + vh.y() * vh.y();
  const Vec3 t1 = lensq > 0 ? Vec3(-vh.y(), vh.x(), 0.0) / std::sqrt(lensq) : Vec3(1.0, 0.0, 0.0);
  const Vec3 t2 = vh.cross(t1);
  // Uniform point on the disk, then warp its lower half onto the projected hemisphere.
  const double r = std::sqrt(u.x());
  const double phi = 2.0 * kPi * u.y();
  const double p1 = r * std::cos(phi);
  double p2 = r * std::sin(phi);
  const double s = 0.5 * (1.0 + vh.z());
  p2 = (1.0 - s) * std::sqrt(std::max(0.0, 1.0 - p1 * p1)) + s * p2;
  // Reproject onto the hemisphere and unstretch.
  const Vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
  return Vec3(alpha * nh.x(), alpha * nh.y(), std::max(0.0, nh.z())).normalized();
}

double ggx_visible_normal_pdf(double alpha, const Vec3& v, const Vec3& m) {
  if (!(v.z() > 0)) return 0.0;
  const double vm = v.dot(m);
  if (!(vm > 0)) return 0.0;
  return ggx_G1<double>(alpha, v, m) * vm * ggx_D<double>(alpha, m) / v.z();
}

double ggx_reflection_pdf(double alpha, const Vec3& wi, const Vec3& wo) {
  if (!(wo.z() > 0)) return 0.0;
  const Vec3 hs = wi + wo;
  const double n2 = hs.squaredNorm();
  if (!(n2 > 0)) return 0.0;  // wi = -wo: reached only in the limit wo.m -> 0 (measure zero)
  const Vec3 m = hs / std::sqrt(n2);
  // D_wo(m) / (4 wo.m) with D_wo(m) = G1(wo,m) (wo.m) D(m) / wo.z: the wo.m cancels.
  return ggx_G1<double>(alpha, wo, m) * ggx_D<double>(alpha, m) / (4.0 * wo.z());
}

namespace {
/// Mirrors a local direction to the other side of the surface (z -> -z).
Vec3 flip_z(const Vec3& v) { return {v.x(), v.y(), -v.z()}; }

/// Density of the diffuse proposal: `share` uniform over the hemisphere, the rest cosine-weighted.
double diffuse_pdf(double cos_theta, double share) {
  return cos_theta > 0 ? share * uniform_hemisphere_pdf(cos_theta) + (1.0 - share) * cosine_hemisphere_pdf(cos_theta)
                       : 0.0;
}
}  // namespace

BSDFSample bsdf_sample(const BSDFDesc& b, const Vec3& wo_in, const Vec2& u, double uniform_share) {
  QSIL_DCHECK_MSG(uniform_share >= 0 && uniform_share < 1, "uniform share " << uniform_share);
  BSDFSample s;
  Vec3 wo = wo_in;
  const bool flipped = wo.z() < 0;
  if (flipped) {
    if (!b.twosided) return s;
    wo = flip_z(wo);
  }
  if (!(wo.z() > 0)) return s;

  switch (b.type) {
    case BSDFDesc::Type::Diffuse: {
      // u.x chooses the component and is then rescaled to [0,1) for it.
      s.wi = u.x() < uniform_share
                 ? square_to_uniform_hemisphere(Vec2(u.x() / uniform_share, u.y()))
                 : square_to_cosine_hemisphere(Vec2((u.x() - uniform_share) / (1.0 - uniform_share), u.y()));
      s.pdf = diffuse_pdf(s.wi.z(), uniform_share);
      break;
    }
    case BSDFDesc::Type::RoughConductor: {
      const double alpha = ggx_alpha(b);
      const Vec3 m = ggx_sample_visible_normal(alpha, wo, u);
      s.wi = reflect(wo, m);
      // pdf from the sampled m (not from normalize(wi + wo)): same value, less rounding.
      s.pdf = ggx_G1<double>(alpha, wo, m) * ggx_D<double>(alpha, m) / (4.0 * wo.z());
      break;
    }
  }
  s.valid = s.wi.z() > 0 && s.pdf > 0;
  if (flipped) s.wi = flip_z(s.wi);
  return s;
}

double bsdf_pdf(const BSDFDesc& b, const Vec3& wi_in, const Vec3& wo_in, double uniform_share) {
  Vec3 wi = wi_in, wo = wo_in;
  if (wo.z() < 0) {
    if (!b.twosided) return 0.0;
    wi = flip_z(wi);
    wo = flip_z(wo);
  }
  if (!(wo.z() > 0)) return 0.0;
  switch (b.type) {
    case BSDFDesc::Type::Diffuse: return diffuse_pdf(wi.z(), uniform_share);
    case BSDFDesc::Type::RoughConductor: return ggx_reflection_pdf(ggx_alpha(b), wi, wo);
  }
  return 0.0;
}

}  // namespace qsil
