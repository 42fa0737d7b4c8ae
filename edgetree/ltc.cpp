/// @file ltc.cpp
/// LTC lookup, evaluation and spherical polygon integrals (see ltc.h; Heitz et al. 2016).

#include "qsil/edgetree/ltc.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace qsil::edgetree {
namespace {

/// The fitted table: [alpha node][cos node] = {m00, m02, m20, m22, norm} (layout in ltc.h).
constexpr double kTable[kLTCAlphaCount][kLTCCosCount][5] = {
#include "ltc_ggx_table.inc"
};

/// atan2(y, x) by a degree-11 odd minimax polynomial on [0, 1] with octant reduction: absolute
/// error < 1e-5 rad and relative error < 3e-5 near 0, about 5x faster than libm. Used only where
/// the value steers sampling (node importance), never where it is an estimate: an importance
/// needs no accuracy, only consistency between the choice and its probability.
double fast_atan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double mx = std::max(ax, ay), mn = std::min(ax, ay);
  if (!(mx > 0)) return 0.0;
  const double a = mn / mx, s = a * a, s2 = s * s, s4 = s2 * s2;
  // Estrin's scheme (pairs, then s^2 and s^4): a shorter dependency chain than Horner's.
  double r = a * ((0.99997726 - 0.33262347 * s) + s2 * (0.19354346 - 0.11643287 * s) +
                  s4 * (0.05265332 - 0.01172120 * s));
  if (ay > ax) r = 0.5 * kPi - r;
  if (x < 0) r = kPi - r;
  return y < 0 ? -r : r;
}

/// (1/2pi) * angle(a, b) * normalize(a x b).z: the contribution of the great arc a -> b to the
/// Lambert form factor ([LTC] Eq. 11). atan2 of |a x b| and a.b keeps the angle accurate for
/// nearly parallel and nearly antiparallel a, b and is independent of |a|, |b|. A zero-length
/// arc contributes 0.
template <bool Fast>
double edge_form_factor(const Vec3& a, const Vec3& b) {
  const Vec3 c = a.cross(b);
  const double cn = c.norm();
  if (!(cn > 0.0)) return 0.0;
  const double angle = Fast ? fast_atan2(cn, a.dot(b)) : std::atan2(cn, a.dot(b));
  return angle * (c.z() / cn);
}

/// Form factor of a polygon already inside z >= 0 (signed sum, absolute value).
template <bool Fast>
double form_factor(std::span<const Vec3> poly) {
  const size_t n = poly.size();
  if (n < 3) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) sum += edge_form_factor<Fast>(poly[i], poly[(i + 1) % n]);
  return std::min(1.0, std::abs(sum) * (0.5 * kInvPi));
}

void check_size(std::span<const Vec3> poly) {
  if (poly.size() > static_cast<size_t>(kMaxPolygonVertices))
    throw std::invalid_argument("LTC polygon routines: more than kMaxPolygonVertices vertices");
}

/// One table entry interpolated bilinearly at fractional indices (fa, fc).
void lookup(double fa, double fc, double out[5]) {
  fa = std::clamp(fa, 0.0, double(kLTCAlphaCount - 1));
  fc = std::clamp(fc, 0.0, double(kLTCCosCount - 1));
  const int ia = std::min(int(fa), kLTCAlphaCount - 2);
  const int ic = std::min(int(fc), kLTCCosCount - 2);
  const double ta = fa - ia, tc = fc - ic;
  for (int k = 0; k < 5; ++k) {
    const double v00 = kTable[ia][ic][k], v01 = kTable[ia][ic + 1][k];
    const double v10 = kTable[ia + 1][ic][k], v11 = kTable[ia + 1][ic + 1][k];
    out[k] = (1 - ta) * ((1 - tc) * v00 + tc * v01) + ta * ((1 - tc) * v10 + tc * v11);
  }
}

}  // namespace

LTC ltc_diffuse() { return LTC{}; }

LTC ltc_ggx(double alpha, const Vec3& wo_local) {
  LTC ltc;
  const double len = wo_local.norm();
  if (!(len > 0.0) || !(wo_local.z() > 0.0) || !std::isfinite(len)) {
    ltc.norm = 0.0;
    return ltc;
  }
  const Vec3 wo = wo_local / len;
  const double a = std::clamp(std::isfinite(alpha) ? alpha : 1.0, kLTCMinAlpha, 1.0);
  const double fa = (1.0 - std::log(a) / std::log(kLTCMinAlpha)) * (kLTCAlphaCount - 1);
  const double v = std::sqrt(std::max(0.0, 1.0 - std::min(1.0, wo.z())));
  const double fc = v * (kLTCCosCount - 1);
  double e[5];
  lookup(fa, fc, e);
  Mat3 Mc;
  Mc << e[0], 0.0, e[1],  //
      0.0, 1.0, 0.0,      //
      e[2], 0.0, e[3];
  // Rotation about z taking wo's azimuth to the canonical x axis: w_canonical = Rz(-phi) w.
  const double r = std::hypot(wo.x(), wo.y());
  double c = 1.0, s = 0.0;
  if (r > 0.0) {
    c = wo.x() / r;
    s = wo.y() / r;
  }
  Mat3 Rm;
  Rm << c, s, 0.0,  //
      -s, c, 0.0,   //
      0.0, 0.0, 1.0;
  ltc.M_inv = Mc * Rm;
  ltc.det_M_inv = Mc.determinant();
  ltc.norm = std::max(0.0, e[4]);
  return ltc;
}

LTCCone ltc_core_cone(const LTC& ltc, double mass) {
  LTCCone cone;
  const Mat3 M = ltc.M_inv.inverse();
  const Vec3 axis = M.col(2);
  if (!(axis.squaredNorm() > 0) || !axis.allFinite()) return cone;
  cone.axis = axis.normalized();
  const double s = std::sqrt(std::clamp(mass, 0.0, 1.0)), c = std::sqrt(std::max(0.0, 1.0 - mass));
  // Rim directions at multiples of 2 pi / 16: (cos, sin) of 0, pi/8, .., 7 pi/8; the other eight
  // are their negatives.
  static constexpr double kCos[8] = {1.0, 0.92387953251128674,  0.70710678118654757,  0.38268343236508984,
                                     0.0, -0.38268343236508984, -0.70710678118654757, -0.92387953251128674};
  static constexpr double kSin[8] = {0.0, 0.38268343236508978, 0.70710678118654746, 0.92387953251128674,
                                     1.0, 0.92387953251128674, 0.70710678118654757, 0.38268343236508984};
  const Vec3 centre = c * axis;  // M (0, 0, c)
  double lowest = 1.0;
  for (int i = 0; i < 8; ++i) {
    const Vec3 side = s * (kCos[i] * M.col(0) + kSin[i] * M.col(1));
    lowest =
        std::min({lowest, (centre + side).normalized().dot(cone.axis), (centre - side).normalized().dot(cone.axis)});
  }
  cone.cos_half_angle = lowest;
  return cone;
}

double ltc_eval(const LTC& ltc, const Vec3& w) {
  if (!(w.z() > 0.0)) return 0.0;
  const Vec3 wc = ltc.M_inv * w;
  if (!(wc.z() > 0.0)) return 0.0;
  const double wn = w.norm();
  const double l = wc.norm() / wn;  // |M_inv w| for the unit w
  // D_o(wc/|wc|) |det| / |M_inv w|^3 with D_o = z/pi.
  return (wc.z() / (l * wn)) * kInvPi * std::abs(ltc.det_M_inv) / (l * l * l);
}

SmallPolygon clip_polygon_to_halfspace(std::span<const Vec3> poly, const Vec3& n) {
  check_size(poly);
  SmallPolygon out;
  const size_t cnt = poly.size();
  for (size_t i = 0; i < cnt; ++i) {
    const Vec3& a = poly[i];
    const Vec3& b = poly[(i + 1) % cnt];
    const double da = n.dot(a), db = n.dot(b);
    if (da >= 0.0) out.push(a);
    if ((da >= 0.0) != (db >= 0.0)) {
      const double t = da / (da - db);  // da != db here
      out.push(a + t * (b - a));
    }
  }
  return out;
}

double cosine_polygon_integral(std::span<const Vec3> poly) {
  if (poly.size() < 3) return 0.0;
  const SmallPolygon c = clip_polygon_to_halfspace(poly, Vec3::UnitZ());
  return form_factor<false>(c.span());
}

double ltc_polygon_integral(const LTC& ltc, std::span<const Vec3> poly, bool fast) {
  if (poly.size() < 3) return 0.0;
  const SmallPolygon up = clip_polygon_to_halfspace(poly, Vec3::UnitZ());
  if (up.count < 3) return 0.0;
  // The cosine lobe (a diffuse BSDF's, ltc_diffuse): M_inv = I maps the clipped polygon to itself,
  // already inside z >= 0; the transform and the second clip would change it only by rounding
  // (an intersection point's z = ±1e-17 re-clipped).
  if (is_cosine_lobe(ltc)) return fast ? form_factor<true>(up.span()) : form_factor<false>(up.span());
  SmallPolygon t;
  for (int i = 0; i < up.count; ++i) t.push(ltc.M_inv * up.v[size_t(i)]);
  const SmallPolygon c = clip_polygon_to_halfspace(t.span(), Vec3::UnitZ());
  return fast ? form_factor<true>(c.span()) : form_factor<false>(c.span());
}

double polygon_solid_angle(std::span<const Vec3> poly, bool fast) {
  const size_t n = poly.size();
  if (n < 3) return 0.0;
  const Vec3& a = poly[0];
  const double la = a.norm();
  double sum = 0.0;
  for (size_t i = 1; i + 1 < n; ++i) {
    const Vec3& b = poly[i];
    const Vec3& c = poly[i + 1];
    const double lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    sum += 2.0 * (fast ? fast_atan2(num, den) : std::atan2(num, den));
  }
  return std::abs(sum);
}

namespace {

/// The outline of `box` from p by the convex hull of the 8 corners in a central projection
/// (Andrew's monotone chain): the construction of the region table below, run once per region.
BoxSilhouette box_silhouette_hull(const Box3& box, const Vec3& p) {
  BoxSilhouette out;
  if (box.empty()) return out;
  // An axis along which p is outside the slab: every corner lies strictly in front of the plane
  // through p perpendicular to it. Take the one with the largest gap relative to the box size.
  int axis = -1;
  double best = -1.0, sign = 0.0;
  const Vec3 ext = box.extent();
  const double size = std::max(ext.maxCoeff(), 0.0);
  for (int k = 0; k < 3; ++k) {
    double gap = 0.0, s = 0.0;
    if (p[k] < box.lo[k]) {
      gap = box.lo[k] - p[k];
      s = 1.0;
    } else if (p[k] > box.hi[k]) {
      gap = p[k] - box.hi[k];
      s = -1.0;
    } else {
      continue;
    }
    const double score = gap / (ext[k] + size + gap);  // scale-free
    if (score > best) {
      best = score;
      axis = k;
      sign = s;
    }
  }
  if (axis < 0) {
    out.inside = true;
    return out;
  }
  int ku = (axis + 1) % 3, kv = (axis + 2) % 3;
  if (sign < 0) std::swap(ku, kv);  // so that e_ku x e_kv = d = sign * e_axis
  struct P2 {
    double x, y;
    int corner;
  };
  std::array<P2, 8> pts;
  std::array<Vec3, 8> rel;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? box.hi.x() : box.lo.x(), (c & 2) ? box.hi.y() : box.lo.y(),
                      (c & 4) ? box.hi.z() : box.lo.z());
    rel[size_t(c)] = corner - p;
    const double depth = sign * rel[size_t(c)][axis];  // > 0
    pts[size_t(c)] = {rel[size_t(c)][ku] / depth, rel[size_t(c)][kv] / depth, c};
  }
  // Andrew's monotone chain, counter-clockwise, collinear and duplicate points dropped.
  std::sort(pts.begin(), pts.end(), [](const P2& a, const P2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  auto cross = [](const P2& o, const P2& a, const P2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  std::array<P2, 16> hull;
  int h = 0;
  for (int i = 0; i < 8; ++i) {
    while (h >= 2 && cross(hull[size_t(h - 2)], hull[size_t(h - 1)], pts[size_t(i)]) <= 0) --h;
    hull[size_t(h++)] = pts[size_t(i)];
  }
  for (int i = 6, lower = h + 1; i >= 0; --i) {
    while (h >= lower && cross(hull[size_t(h - 2)], hull[size_t(h - 1)], pts[size_t(i)]) <= 0) --h;
    hull[size_t(h++)] = pts[size_t(i)];
  }
  --h;  // the last point repeats the first
  for (int i = 0; i < h; ++i) out.polygon.push(rel[size_t(hull[size_t(i)].corner)]);
  return out;
}

/// Region of p against an axis-aligned box: per axis 0 inside the closed slab, 1 below, 2 above;
/// code = sum_k region_k 3^k (0: p in the closed box).
int box_region(const Box3& box, const Vec3& p) {
  int code = 0;
  for (int k = 2; k >= 0; --k) code = 3 * code + (p[k] < box.lo[k] ? 1 : (p[k] > box.hi[k] ? 2 : 0));
  return code;
}

/// Per region code, the outline's corners (bit k of a corner index: hi on axis k) in order, -1
/// terminated. Within a region the set of faces p sees is fixed (a face is seen iff p lies
/// beyond its plane), so the outline's corners and their cyclic order are too: each entry is the
/// hull construction's answer for one point of its region and the unit box (Schmalstieg &
/// Tobler 1999, "Fast projected area computation for three-dimensional bounding boxes", JGT 4(2),
/// tabulate the same outlines by hand).
const std::array<std::array<int, 7>, 27>& box_outline_table() {
  static const std::array<std::array<int, 7>, 27> table = [] {
    std::array<std::array<int, 7>, 27> t{};
    Box3 unit;
    unit.expand(Vec3::Zero());
    unit.expand(Vec3::Ones());
    const double coord[3] = {0.5, -1.0, 2.0};  // inside the slab, below, above
    for (int code = 0; code < 27; ++code) {
      t[size_t(code)].fill(-1);
      if (code == 0) continue;
      const Vec3 p(coord[code % 3], coord[(code / 3) % 3], coord[code / 9]);
      const BoxSilhouette s = box_silhouette_hull(unit, p);
      for (int i = 0; i < s.polygon.count; ++i) {
        const Vec3 c = s.polygon.v[size_t(i)] + p;
        t[size_t(code)][size_t(i)] = (c.x() > 0.5 ? 1 : 0) | (c.y() > 0.5 ? 2 : 0) | (c.z() > 0.5 ? 4 : 0);
      }
    }
    return t;
  }();
  return table;
}

}  // namespace

BoxSilhouette box_silhouette_polygon(const Box3& box, const Vec3& p) {
  BoxSilhouette out;
  if (box.empty()) return out;
  const int code = box_region(box, p);
  if (code == 0) {
    out.inside = true;
    return out;
  }
  // The region's corners relative to p; a flat box's coinciding corners (always neighbours on
  // the outline: they are the ends of a zero-length box edge) are kept once.
  std::array<Vec3, 6> v;
  int n = 0;
  for (int c : box_outline_table()[size_t(code)]) {
    if (c < 0) break;
    const Vec3 r =
        Vec3((c & 1) ? box.hi.x() : box.lo.x(), (c & 2) ? box.hi.y() : box.lo.y(), (c & 4) ? box.hi.z() : box.lo.z()) -
        p;
    if (n > 0 && r == v[size_t(n - 1)]) continue;
    v[size_t(n++)] = r;
  }
  while (n > 1 && v[size_t(n - 1)] == v[0]) --n;
  if (n < 3) return out;  // seen edge-on: no solid angle
  for (int i = 0; i < n; ++i) out.polygon.push(v[size_t(i)]);
  return out;
}

}  // namespace qsil::edgetree
