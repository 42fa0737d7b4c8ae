#pragma once
/// @file warp_field.h
/// Warped-area sampling (`--boundary was`, docs/architecture.md §15): Bangaru, Li, Durand 2020,
/// "Unbiased Warped-Area Sampling for Differentiable Rendering", ACM TOG 39(6), cited as [WAS].
///
/// Instead of fixing a sampled direction w and adding the boundary term it leaves out, the
/// direction is moved with theta by a warp field V(w) that, at every discontinuity of the
/// integrand, moves with the discontinuity ([WAS] Eq. 7-9): the integral of f over the sphere
/// equals that of f(T(w)) det(dT/dw) with T(w) = normalize(w + theta V(w)), and the derivative of
/// the second integrand, f's change along the warped direction plus f div V, has no boundary
/// term ([WAS] Eq. 10). V is a weighted mean of the velocities of auxiliary rays around w
/// ([WAS] §5, Eq. 16-18), with harmonic weights that grow without bound where an auxiliary ray
/// both lies on w and hits a triangle's edge, so that at a silhouette the mean is the
/// silhouette's own velocity:
///   V(w)   = sum_i K_i v_i / sum_i K_i,   K_i = (D(w, w_i) + B_i)^-gamma / q(w_i | w),
///   D      = exp(kappa (1 - w.w_i)) - 1,  w_i ~ q = vMF(w, kappa),
///   v_i    = d/dtheta normalize(y_i(theta) - p(theta)): y_i the auxiliary hit attached to its
///            triangle (fixed barycentrics), p the shading point (velocities relative to p);
///            0 for a ray that escapes,
///   div V  = (sum_i grad_w K_i . v_i - V . sum_i grad_w K_i) / sum_i K_i - 2 w.V
///            (the last term: the divergence on the sphere of V's tangent part, which the warp uses),
///   grad_w K_i = gamma kappa (D + 1) (D + B_i)^-gamma-1 (w_i - (w_i.w) w) / q.
/// B_i (triangle_boundary_test) is 0 on the hit triangle's edges and 1 at the incentre of the
/// triangle's projection along w_i. N auxiliary rays give a ratio estimate: [WAS]'s biased
/// fixed-N variant (its bias shrinks as N grows; measured in docs/experiments/). Pdfs and MIS
/// weights stay detached: the weights partition unity over the unwarped direction, and each
/// strategy's estimate there is linear in the field it drew, drawn alike by every strategy
/// (docs/design-notes.md "Warped-area sampling").

#include "qsil/dual.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/integrators/surface_interaction.h"
#include "qsil/integrators/warped_area_sampling.h"
#include "qsil/ray_tracer.h"
#include "qsil/rng.h"
#include "qsil/sampling.h"

#include <algorithm>
#include <cmath>

namespace qsil {

/// Where an auxiliary ray meets the edges of the triangle (a, b, c) it hit at y, seen along unit
/// direction `dir`: the distance from y to the nearest edge of the triangle's projection on the
/// plane normal to dir, over the projection's inradius: 0 on an edge (and for a triangle seen
/// edge-on), 1 at the incentre. Scale-free: the same for any scene size.
inline double triangle_boundary_test(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& y, const Vec3& dir) {
  const Frame f(dir);
  const auto project = [&](const Vec3& v) {
    const Vec3 l = f.to_local(Vec3(v - y));
    return Vec2(l.x(), l.y());
  };
  const Vec2 P[3] = {project(a), project(b), project(c)};
  const auto cross = [](const Vec2& u, const Vec2& v) { return u.x() * v.y() - u.y() * v.x(); };
  double nearest = kInf, perimeter = 0;
  for (int e = 0; e < 3; ++e) {
    const Vec2& p = P[e];
    const Vec2& q = P[(e + 1) % 3];
    const double len = (q - p).norm();
    perimeter += len;
    nearest = std::min(nearest, len > 0 ? std::abs(cross(p, q)) / len : 0.0);
  }
  const double twice_area = std::abs(cross(Vec2(P[1] - P[0]), Vec2(P[2] - P[0])));
  if (!(twice_area > 0) || !(perimeter > 0)) return 0.0;
  return std::clamp(nearest * perimeter / twice_area, 0.0, 1.0);
}

/// A warped direction: unit in value, its derivatives the warp field V_k (tangent at the
/// direction, one per parameter), and the Jacobian determinant of the warp, value 1, derivatives
/// div V_k.
template <class T>
struct WarpedDirection {
  Vec3T<T> dir;
  T jacobian;
};

/// Sums over auxiliary rays of a warp field's ratio estimate (warp_field): sum K_i, sum grad_w
/// K_i, sum K_i v_i (per parameter) and sum grad_w K_i . v_i.
template <int N>
struct WarpSums {
  double Z = 0;
  Vec3 dZ = Vec3::Zero();
  Eigen::Matrix<double, 3, N> KV = Eigen::Matrix<double, 3, N>::Zero();
  Eigen::Matrix<double, 1, N> gV = Eigen::Matrix<double, 1, N>::Zero();
  WarpSums operator+(const WarpSums& o) const { return {Z + o.Z, dZ + o.dZ, KV + o.KV, gV + o.gV}; }
};

/// A warp field and its divergence at one direction, per parameter.
template <int N>
struct WarpEstimate {
  Eigen::Matrix<double, 3, N> V = Eigen::Matrix<double, 3, N>::Zero();
  Eigen::Matrix<double, 1, N> div = Eigen::Matrix<double, 1, N>::Zero();
  /// The ratio estimate of sums: V = KV / Z, div V = (gV - dZ . V) / Z; zero without weight.
  static WarpEstimate ratio(const WarpSums<N>& s) {
    WarpEstimate e;
    if (!(s.Z > 0) || !std::isfinite(s.Z)) return e;
    e.V = s.KV / s.Z;
    e.div = (s.gV - s.dZ.transpose() * e.V) / s.Z;
    return e;
  }
};

/// The warp of direction `w` (world, unit) leaving point `p` (over T: it may move): auxiliary
/// rays, the i-th from `spawn(w_i)` (p offset as the path's own rays are) with
/// `through_back_faces` as the path's ray toward w, drawn with `aux` and counted in stats.rays;
/// `was.rays` of them for the fixed-N estimate, rays x 2^L for the unbiased one.
/// `p_constant`: p has zero derivatives (then only hits on moving shapes have a velocity).
/// View: DualView<N>.
template <class View, class Spawn>
WarpedDirection<typename View::Real> warp_field(const PathContext& ctx, const View& view, const WarpedAreaSampling& was,
                                                const Vec3T<typename View::Real>& p, bool p_constant, const Vec3& w,
                                                const Spawn& spawn, bool through_back_faces, Sampler& aux,
                                                PathStats& stats) {
  using T = typename View::Real;
  constexpr int N = T::DerType::RowsAtCompileTime;
  const Frame frame(w);
  // Adds one auxiliary ray to `sums`.
  const auto add_ray = [&](WarpSums<N>& sums) {
    const VonMisesFisherSample s = square_to_von_mises_fisher(aux.next2(), was.kappa);
    const Vec3 wi = frame.to_world(s.dir).normalized();
    const Vec3 tangent = frame.s * s.dir.x() + frame.t * s.dir.y();  // w_i - (w_i.w) w
    IgnoreSet ignore;
    ignore.through_back_faces = through_back_faces;
    const Vec3 origin = spawn(wi);
    const Hit hit = ctx.tracer->intersect(origin, wi, kInf, ignore);
    ++stats.rays;
    double B = 1;
    Eigen::Matrix<double, 3, N> v = Eigen::Matrix<double, 3, N>::Zero();
    if (hit.valid()) {
      const SurfaceInteraction<double> h =
          make_interaction(PrimalView{ctx.scene}, hit, origin, wi, ctx.tracer->local_origin());
      const Shape& shape = ctx.scene->shapes[hit.shape];
      const Eigen::Vector3i& tri = shape.mesh.triangles[hit.triangle];
      const auto& P = shape.mesh.positions;
      B = triangle_boundary_test(P[tri[0]], P[tri[1]], P[tri[2]], h.p, wi);
      if (view.moving(hit.shape) || !p_constant) {
        // The hit attached to its triangle, seen from the (moving) point p.
        const Vec3T<T> y = view.position(hit.shape, tri[0]) * T(1.0 - h.b1 - h.b2) +
                           view.position(hit.shape, tri[1]) * T(h.b1) + view.position(hit.shape, tri[2]) * T(h.b2);
        const Vec3T<T> to = y - p;
        using std::sqrt;
        const Vec3T<T> dir = to / sqrt(to.squaredNorm());
        for (int r = 0; r < 3; ++r) v.row(r) = dir[r].derivatives().transpose();
      }
    }
    // K_i q(w_i | w) up to the vMF's constant (it cancels in the ratios): (D + 1) (D + B)^-gamma.
    const double D = std::expm1(was.kappa * s.one_minus_cos);
    if (!std::isfinite(D)) return;                 // the weight's limit is 0 (gamma > 1): the ray adds nothing
    const double inv_denominator = 1.0 / (D + B);  // D > 0: s.one_minus_cos > 0 for u < 1
    const double K = (D + 1) * std::pow(inv_denominator, was.exponent);
    const Vec3 gK = (was.exponent * was.kappa * (D + 1) * K * inv_denominator) * tangent;
    sums.Z += K;
    sums.dZ += gK;
    sums.KV += K * v;
    sums.gV += gK.transpose() * v;
  };
  WarpEstimate<N> e;
  if (!was.unbiased) {
    WarpSums<N> sums;
    for (int i = 0; i < was.rays; ++i) add_ray(sums);
    e = WarpEstimate<N>::ratio(sums);
  } else {
    // Level L by inversion of P(L >= l) = r^l, truncated at max_level; the estimate
    // Delta_L / P(L = l), the highest level's P(L >= max_level).
    int max_level = 0;
    while ((was.rays << (max_level + 1)) <= kWarpMaxRays) ++max_level;
    const int level = std::min(max_level, int(std::log1p(-aux.next()) / std::log(kWarpLevelRatio)));
    const double p_level = (level < max_level ? 1 - kWarpLevelRatio : 1.0) * std::pow(kWarpLevelRatio, double(level));
    const int half = level == 0 ? was.rays : was.rays << (level - 1);
    WarpSums<N> a, b;
    for (int i = 0; i < half; ++i) add_ray(a);
    if (level > 0)
      for (int i = 0; i < half; ++i) add_ray(b);
    const WarpEstimate<N> whole = WarpEstimate<N>::ratio(a + b);
    if (level == 0) {
      e.V = whole.V / p_level;
      e.div = whole.div / p_level;
    } else {
      const WarpEstimate<N> ea = WarpEstimate<N>::ratio(a), eb = WarpEstimate<N>::ratio(b);
      e.V = (whole.V - 0.5 * (ea.V + eb.V)) / p_level;
      e.div = (whole.div - 0.5 * (ea.div + eb.div)) / p_level;
    }
  }
  WarpedDirection<T> r;
  r.dir = lift<T>(w);
  r.jacobian = T(1.0);
  // The field the warp uses is V's tangent part P V (the v_i are tangent at their own w_i, not
  // at w): its divergence on the sphere is div V - 2 w.V.
  e.div -= 2.0 * (w.transpose() * e.V);
  e.V -= w * (w.transpose() * e.V);
  for (int c = 0; c < 3; ++c) r.dir[c].derivatives() = e.V.row(c).transpose();
  r.jacobian.derivatives() = e.div.transpose();
  return r;
}

/// The warp of direction `w` (world, unit) leaving shading point `si` seen from `wo_world`:
/// warp_field from si.p, the auxiliary rays offset as the path's (spawn_origin).
template <class View>
WarpedDirection<typename View::Real> warp_direction(const PathContext& ctx, const View& view,
                                                    const WarpedAreaSampling& was,
                                                    const SurfaceInteraction<typename View::Real>& si,
                                                    const Vec3& wo_world, const Vec3& w, Sampler& aux,
                                                    PathStats& stats) {
  return warp_field(
      ctx, view, was, si.p, si.constant, w, [&](const Vec3& wi) { return spawn_origin(si, wi); },
      leaves_below(si, wo_world, w), aux, stats);
}

/// Film position (pixels, Camera::project) of the unit world direction `d` from the camera, over
/// T: its derivatives are the film velocity of a warped direction.
template <class T>
Vec2T<T> film_position(const Camera& camera, const Vec3T<T>& d) {
  const Eigen::Matrix3d R = camera.to_world.block<3, 3>(0, 0);
  Vec3T<T> c;
  for (int i = 0; i < 3; ++i) c[i] = d.x() * R(0, i) + d.y() * R(1, i) + d.z() * R(2, i);
  const Vec2 t = camera.tan_half_fov();
  return Vec2T<T>(T(0.5 * camera.width) * (T(1.0) - c.x() / (c.z() * t.x())),
                  T(0.5 * camera.height) * (T(1.0) - c.y() / (c.z() * t.y())));
}

/// The warp of a camera ray's direction `d` (world, unit) over the film: warp_field from the
/// camera's origin, with the Jacobian of the film's warp S = U T U^-1 (U: direction -> film
/// position), det(dS/du) = det(dT/dw) G(T(w)) / G(w), G(w) = f^2 / cos^3 of w's angle to the
/// optical axis (film area per steradian), so that a pixel's integral over film position,
/// L(S(u)) det(dS/du), holds its value.
template <class View>
WarpedDirection<typename View::Real> warp_camera_direction(const PathContext& ctx, const View& view,
                                                           const WarpedAreaSampling& was, const Vec3& d, Sampler& aux,
                                                           PathStats& stats) {
  using T = typename View::Real;
  const Camera& camera = ctx.scene->camera;
  const Vec3 o = camera.origin();
  WarpedDirection<T> r = warp_field(
      ctx, view, was, lift<T>(o), true, d, [&](const Vec3&) { return o; }, false, aux, stats);
  const Vec3 axis = camera.to_world.block<3, 1>(0, 2).normalized();
  const T ratio = T(d.dot(axis)) / r.dir.dot(lift<T>(axis));  // cos(w) / cos(T(w))
  r.jacobian = r.jacobian * ratio * ratio * ratio;
  return r;
}

/// The warp of a path's directions under warped-area sampling (trace_path's `Warp`): each
/// direction the path samples at a vertex, toward the next vertex or toward a light, is warped
/// by warp_direction with auxiliary rays drawn from `aux`; the path's first direction is
/// `*first` (a camera ray's warp_camera_direction), or fixed when null.
template <class View>
struct DirectionWarp {
  using T = typename View::Real;
  static constexpr bool enabled = true;
  const PathContext* ctx;
  const View* view;
  WarpedAreaSampling was;
  Sampler* aux;
  const Vec3T<T>* first = nullptr;
  WarpedDirection<T> operator()(const SurfaceInteraction<T>& si, const Vec3& wo_world, const Vec3& w,
                                PathStats& stats) const {
    return warp_direction(*ctx, *view, was, si, wo_world, w, *aux, stats);
  }
  /// The path's first direction `d` over T.
  Vec3T<T> first_direction(const Vec3& d) const { return first ? *first : lift<T>(d); }
};

/// One pixel sample of warped-area sampling, over View's scalar type (DualView<N>): radiance and
/// derivatives of pixel (x, y) from the camera ray `ray` (through film position (x, y) + the
/// sample's offset; trace_camera_ray):
/// - the camera ray's direction warped (warp_camera_direction) and every direction of its path
///   (DirectionWarp), times the film warp's Jacobian;
/// - the pixel border term. A box pixel's integral over the warped film, L(S(u)) det(dS/du) over
///   the pixel, is that of L over the pixel moved by the warp: its derivative counts the flux
///   of L V through the pixel's border, which the pixel does not have. So the sample adds
///   -L(b) V(b).n(b) times the perimeter (4 pixels) at a point b drawn uniformly on the border
///   (n outward; L the radiance of a primal path through b, V the film velocity of b's warp).
/// Streams: `sampler` the path's (after the two numbers that placed the ray), `aux` the auxiliary
/// rays, `border` the border point, its path and its auxiliary rays.
template <class View>
ColorT<typename View::Real> warped_pixel_sample(const PathContext& ctx, const View& view, const WarpedAreaSampling& was,
                                                int x, int y, const CameraRay& ray, Sampler& sampler, Sampler& aux,
                                                Sampler& border, PathStats& stats) {
  using T = typename View::Real;
  const Camera& cam = ctx.scene->camera;
  const Vec3 o = cam.origin();
  const WarpedDirection<T> camera_warp = warp_camera_direction(ctx, view, was, ray.dir, aux, stats);
  const DirectionWarp<View> warp{&ctx, &view, was, &aux, &camera_warp.dir};
  ColorT<T> L = trace_path(ctx, view, PathRay<T>{lift<T>(o), ray.dir, ray.hit}, sampler, stats, NoVertexHook{}, warp);
  for (int c = 0; c < 3; ++c) L[c] = L[c] * camera_warp.jacobian;

  // ---- The pixel border term: side 0 top, 1 right, 2 bottom, 3 left (film y grows downward).
  const Vec2 ub = border.next2();
  const int side = std::min(3, int(ub.x() * 4.0));
  const double t = std::min(1.0, ub.x() * 4.0 - side);
  static constexpr double kSide[4][4] = {{0, 0, 0, -1}, {1, 0, 1, 0}, {0, 1, 0, 1}, {0, 0, -1, 0}};
  const double* k = kSide[side];  // film offset (x, y) of the side's start, and its outward normal
  const bool along_x = side % 2 == 0;
  const Vec2 b(x + k[0] + (along_x ? t : 0.0), y + k[1] + (along_x ? 0.0 : t));
  const Vec2 n(k[2], k[3]);
  const Vec3 db = cam.direction(b.x(), b.y());
  ++stats.rays;
  const Hit hb = ctx.tracer->intersect(o, db);
  const Color Lb = trace_path(ctx, PrimalView{ctx.scene}, PathRay<double>{o, db, hb, 0, 0}, border, stats);
  if ((Lb != 0).any()) {
    const WarpedDirection<T> border_warp = warp_camera_direction(ctx, view, was, db, border, stats);
    const Vec2T<T> f = film_position<T>(cam, border_warp.dir);
    const auto vn = f.x().derivatives() * n.x() + f.y().derivatives() * n.y();  // V_film . n, per parameter
    for (int c = 0; c < 3; ++c) L[c].derivatives() -= (4.0 * Lb[c]) * vn;
  }
  return L;
}

}  // namespace qsil
