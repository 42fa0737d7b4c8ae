#pragma once
/// @file bsdf_ltc.h
/// The linearly transformed cosine (LTC, Heitz et al. 2016) that stands for a shading point's BSDF
/// in the edge choice's importance [QSS 3.6]: the clamped cosine for a diffuse BSDF, the fitted
/// GGX table otherwise (ltc.h).

#include "qsil/bsdf.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/math.h"

namespace qsil::edgetree {

/// The LTC of a shading point's BSDF toward wo (local frame), with the albedo weight in norm.
inline LTC bsdf_ltc(const BSDFDesc& b, Vec3 wo_local) {
  if (b.twosided && wo_local.z() < 0) wo_local.z() = -wo_local.z();
  LTC ltc;
  if (b.type == BSDFDesc::Type::Diffuse) {
    ltc = ltc_diffuse();
    ltc.norm = b.reflectance.mean();
  } else {
    ltc = ltc_ggx(b.alpha, wo_local);
    ltc.norm *= b.specular_reflectance.mean();
  }
  if (!(wo_local.z() > 0)) ltc.norm = 0;  // a one-sided BSDF seen from behind reflects nothing
  return ltc;
}

}  // namespace qsil::edgetree
