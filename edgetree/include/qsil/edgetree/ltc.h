#pragma once
/// @file ltc.h
/// Linearly transformed cosines (LTC) approximating qsil's own GGX BSDF, and the spherical
/// polygon integrals the importance of edge-forest nodes needs (docs/architecture.md §5 "Importance", "LTC";
/// [QSS] Sec. 3.5, 3.6).
///
/// Source: Heitz, Dupuy, Hill, Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly
/// Transformed Cosines", ACM TOG 35(4) (cited [LTC]): a distribution D(w) obtained from the
/// clamped cosine D_o(w_o) = max(0, w_o.z)/pi by the linear map w = M w_o / |M w_o| has density
///   D(w) = D_o(M^-1 w / |M^-1 w|) * |det M^-1| / |M^-1 w|^3        ([LTC] Eq. 1-2)
/// and its integral over a spherical polygon P equals the integral of D_o over the polygon
/// M^-1 P, i.e. the Lambert form factor of M^-1 P clipped to z >= 0 ([LTC] Eq. 11; Arvo 1995).
///
/// Frame: every direction and point is in the LOCAL shading frame of p (z = shading normal); the
/// table is fitted with wo in the xz-plane (wo.x >= 0) and ltc_ggx rotates the LTC about z to wo's
/// azimuth. A "polygon" is a list of points relative to p (or directions, not necessarily unit),
/// projected centrally onto the unit sphere, with great-arc edges each subtending less than pi.
///
/// Support: f_s cos vanishes below the shading horizon, so ltc_eval and ltc_polygon_integral
/// restrict D to w.z > 0 AND to the LTC's own support (M^-1 w).z > 0 (the fitted lobe's mass below
/// the horizon at grazing wo is dropped, as the true BSDF drops it). Callers that need a density
/// > 0 wherever the true integrand can be (docs/architecture.md §5 "Pitfalls") must mix in a
/// defensive term (edge_point_sampler does).

#include "qsil/math.h"

#include <array>
#include <span>

namespace qsil::edgetree {

/// One linearly transformed cosine: norm * D(w) ~= f_s(w, wo) cos(theta_w) for the fitted BSDF.
/// - M_inv: 3x3 matrix mapping a direction w of the LOCAL shading frame (z = shading normal, any
///   azimuth; see the file comment) to the cosine domain. Only its direction matters: D is
///   invariant under scaling M_inv, so the table stores it normalised (M_inv(1,1) = 1 in the
///   canonical frame).
/// - det_M_inv: det(M_inv) (> 0 for a valid LTC).
/// - norm: the directional albedo of the BSDF for this wo, integral over the hemisphere of
///   f_s cos (dimensionless, in [0, 1] for GGX with Fresnel 1). 0 for an LTC that represents no
///   reflection (wo below the surface).
struct LTC {
  Mat3 M_inv = Mat3::Identity();
  double det_M_inv = 1.0;
  double norm = 1.0;
};

/// Lambertian LTC: M_inv = I, norm = 1, so norm * D(w) = max(0, w.z)/pi = f_s cos for a diffuse
/// BSDF of reflectance 1 (multiply by the reflectance). Exact.
LTC ltc_diffuse();

/// Whether `ltc` is the clamped cosine itself (M_inv = I, as ltc_diffuse gives): its polygon
/// integral needs no transform and its density is max(0, w.z)/pi.
inline bool is_cosine_lobe(const LTC& ltc) { return ltc.M_inv == Mat3::Identity(); }

/// LTC of qsil's GGX (ggx_eval_cos in qsil/bsdf.h: Smith separable G, Fresnel 1) for roughness
/// `alpha` and view direction `wo_local` (local shading frame, need not be unit; z > 0 for a
/// reflection; wo.z <= 0 gives norm = 0 — mirror z first for a twosided BSDF).
/// Bilinear lookup in the fitted table edgetree/ltc_ggx_table.inc over (log alpha,
/// sqrt(1 - cos theta_o)); alpha is clamped to [1e-4, 1] (the table's range; rougher GGX lobes
/// are approximated by alpha = 1), then M_inv is rotated about z to wo's azimuth.
/// Multiply norm by specular_reflectance per channel.
LTC ltc_ggx(double alpha, const Vec3& wo_local);

/// A circular cone of directions (local shading frame) bounding an LTC's core; see ltc_core_cone.
struct LTCCone {
  Vec3 axis = Vec3::UnitZ();   ///< unit axis, local frame
  double cos_half_angle = -1;  ///< cosine of the half-angle (-1: the whole sphere)
};

/// The circular cone around an LTC's peak that bounds its core, the image of the cosine-domain
/// cone of half-angle gamma, sin^2 gamma = `mass` (which holds that share of the clamped cosine,
/// [LTC] Eq. 1-2, and so of the LTC before the shading horizon's cut): axis = M (0,0,1)
/// normalised (M = M_inv^-1, the image of the cosine lobe's peak), cos_half_angle = the smallest
/// cosine between the axis and the images of 16 directions on the cosine-domain rim. Sixteen rim
/// directions bound the image (an elliptical cone) to within its curvature between them; the
/// contour set (contour_set.h) needs a cone that follows the lobe, not an exact bound. `mass` in
/// (0, 1) (clamped to [0, 1]). A singular M_inv gives the default (the whole sphere).
LTCCone ltc_core_cone(const LTC& ltc, double mass);

/// The LTC density D(w) per unit solid angle (sr^-1) at direction w (local frame, need not be
/// unit), restricted to the upper shading hemisphere: 0 when w.z <= 0 or (M_inv w).z <= 0.
/// norm * ltc_eval(ltc, w) approximates f_s(w, wo) cos(theta_w).
double ltc_eval(const LTC& ltc, const Vec3& w);

/// Integral of D over the spherical polygon with vertices `poly` (points relative to the shading
/// point, or directions, local frame; either winding; at most kMaxPolygonVertices), restricted
/// to the upper shading hemisphere and the LTC support: the polygon is clipped to z >= 0, mapped
/// by M_inv, clipped to z >= 0 again and integrated with the edge formula
///   (1/2pi) |sum_i angle(v_i, v_i+1) * normalize(v_i x v_i+1).z|      ([LTC] Eq. 11).
/// Dimensionless (a probability, in [0, 1]); multiply by norm for the f_s cos integral.
/// Requires a simple polygon contained in an open hemisphere (true for the outline of a convex
/// body not containing p, e.g. box_silhouette_polygon). Fewer than 3 vertices: 0.
/// `fast`: angles by a polynomial atan2 (relative error < 3e-5): for importance only.
double ltc_polygon_integral(const LTC& ltc, std::span<const Vec3> poly, bool fast = false);

/// Exact Lambert form factor of a spherical polygon: (1/pi) * integral of max(0, cos theta) over
/// the polygon (local frame, z = normal) = the polygon clipped to z >= 0 and the edge formula
/// above. In [0, 1]; a polygon covering the upper hemisphere gives 1. Same input rules as
/// ltc_polygon_integral. Equals ltc_polygon_integral(ltc_diffuse(), poly).
double cosine_polygon_integral(std::span<const Vec3> poly);

/// Solid angle (sr) of the spherical polygon (not clipped to any horizon), by fanning from the
/// first vertex into triangles, each by Van Oosterom & Strackee 1983 ("The solid angle of a plane
/// triangle", IEEE TBME 30(2)): tan(Omega/2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| +
/// (b.c)|a|). Signed fan sum, absolute value at the end, so either winding. An octant gives pi/2.
/// `fast`: as for ltc_polygon_integral.
double polygon_solid_angle(std::span<const Vec3> poly, bool fast = false);

/// Largest polygon the routines above accept (the clipping adds up to two vertices).
inline constexpr int kMaxPolygonVertices = 30;

/// A small fixed-capacity polygon (points relative to the shading point).
struct SmallPolygon {
  std::array<Vec3, kMaxPolygonVertices + 2> v;
  int count = 0;
  std::span<const Vec3> span() const { return {v.data(), static_cast<size_t>(count)}; }
  void push(const Vec3& x) { v[static_cast<size_t>(count++)] = x; }
};

/// Clips the cone spanned by `poly` (points relative to the apex, either winding) to the half
/// space n . x >= 0 through the apex (Sutherland-Hodgman; new vertices interpolated linearly on
/// the chord, which projects onto the great arc). Use it with the planes through p and each edge
/// of a light's polygon (normals pointing inside) to intersect Omega(B_p) with Omega(light)
/// ([QSS] Sec. 3.6). Throws std::invalid_argument when poly has more than kMaxPolygonVertices.
SmallPolygon clip_polygon_to_halfspace(std::span<const Vec3> poly, const Vec3& n);

/// Outline of an axis-aligned box seen from p.
/// - inside = true when p lies in the closed box (the box covers a hemisphere or more of the
///   directions; the caller must treat Omega(B_p) as the whole sphere); the polygon is empty.
/// - Otherwise `polygon` holds the 4 or 6 corners (relative to p, i.e. corner - p, scene units)
///   on the silhouette of the box from p, counter-clockwise about the direction from p to the
///   box; its spherical polygon is exactly Omega(B_p). The corners come from a table over the
///   26 regions of space around the box (which faces p sees; Schmalstieg & Tobler 1999), built
///   once by the convex hull of the 8 corners in a central projection; a flat box's coinciding
///   corners are kept once, and a box seen edge-on (fewer than 3 distinct corners) gives an
///   empty polygon.
/// An empty box gives inside = false and an empty polygon.
struct BoxSilhouette {
  bool inside = false;
  SmallPolygon polygon;
};
BoxSilhouette box_silhouette_polygon(const Box3& box, const Vec3& p);

// ---------------------------------------------------------------------------------------------
// The fitted table (edgetree/ltc_ggx_table.inc, written by tools/tool_fit_ltc.cpp)
// ---------------------------------------------------------------------------------------------

/// Table layout shared by the fitting tool and the lookup.
/// Axis a (kLTCAlphaCount nodes): alpha_i = exp(log(1e-4) * (1 - i/(n-1))), log-uniform from
/// 1e-4 to 1 (GGX lobes scale with alpha, so a log axis resolves small alphas: adjacent nodes
/// differ by 16%).
/// Axis c (kLTCCosCount nodes): v_j = j/(n-1), cos theta_o = 1 - v_j^2 (finer near grazing,
/// as [LTC]'s sqrt(1 - cos) parametrisation), floored at kLTCMinCos for the fit.
/// Entry (i, j) = {m00, m02, m20, m22, norm}: the canonical-frame M_inv (x toward wo) with
/// M_inv(1,1) = 1 and M_inv(0,1) = M_inv(1,0) = M_inv(1,2) = M_inv(2,1) = 0, and the albedo.
inline constexpr int kLTCAlphaCount = 64;
inline constexpr int kLTCCosCount = 64;
inline constexpr double kLTCMinAlpha = 1e-4;
inline constexpr double kLTCMinCos = 1e-3;
/// alpha of table node i.
inline double ltc_table_alpha(int i) {
  return std::exp(std::log(kLTCMinAlpha) * (1.0 - double(i) / (kLTCAlphaCount - 1)));
}
/// cos theta_o of table node j (before the kLTCMinCos floor).
inline double ltc_table_cos(int j) {
  const double v = double(j) / (kLTCCosCount - 1);
  return 1.0 - v * v;
}

}  // namespace qsil::edgetree
