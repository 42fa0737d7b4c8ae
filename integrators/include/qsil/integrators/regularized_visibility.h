#pragma once
/// @file regularized_visibility.h
/// Regularised (blurred) visibility after Quinn 2021, "Regularizing Discontinuities in Ray Traced
/// Global Illumination for Differentiable Rendering" (McGill MSc thesis), §4.1-4.4: the
/// `regularized` method (docs/architecture.md §14). A ray does not stop at the first triangle it
/// hits: it sees every triangle whose plane it crosses near the triangle, each with an opacity
/// that falls off smoothly beyond the triangle's edges, composited front to back. The image is
/// then a continuous function of the vertices wherever surfaces do not cross, and the interior
/// term alone (directions fixed, qsil/integrators/path_tracer.h) differentiates it: no boundary
/// term. The price is bias: the regularised image is not the image, nor its derivative the image's.
///
/// The model, per ray o + t d (d fixed and unit), in scene units:
/// - Opacity: a triangle whose plane the ray crosses at t > 0, at the point x, has alpha = 1 on
///   it and alpha = exp(-delta^2 / w^2) outside, delta the in-plane distance from x to the
///   triangle; w = Regularization::width. A triangle whose back the ray meets (geometric normal .
///   d >= 0) blurs only beyond the edges that bound its mesh (delta to those edges; none: alpha =
///   0 outside). Why: at a silhouette its margin would lie in front of the front face, both opaque
///   at the edge, unlike in shading (a jump at every outline of a closed mesh); a back face of a
///   closed mesh is behind a front face wherever its opacity jumps (docs/design-notes.md
///   "Regularised visibility", measured). A jump remains at outlines of flat-shaded meshes
///   (architecture §14).
/// - Composition: terms sorted by t; term k is seen with weight W_k = alpha_k prod_{j<k} (1 -
///   alpha_j), the background (the environment, or nothing) with W_bg = prod_j (1 - alpha_j); the
///   weights sum to 1, and nothing behind a triangle crossed inside is seen. What the ray sees is
///   sum_k W_k S_k + W_bg L_bg (S_k the radiance leaving triangle k's plane at x_k toward the
///   ray's origin). One term is sampled with probability W (detached; [Quinn Eq. 4.5]) and
///   weighted by W(theta) / W: value 1, derivative d log W.
/// - The same composition serves every ray, next-event estimation included ([Quinn §4.4]'s
///   transmission prod (1 - alpha) for shadow rays): a light point is weighed by the summed
///   weights of the emitter terms its ray sees, so both strategies of MIS estimate one integrand.
/// Departures from the thesis, and why (docs/design-notes.md "Regularised visibility"):
/// - [Eq. 4.1] sets alpha = sigmoid(sign(delta) delta^2 / sigma), 1/2 on every edge: composited,
///   every interior edge of a mesh lets a quarter of what lies behind through. Here alpha is 1 on
///   the triangle and blurs outward only (a Gaussian margin, C^1 at the edge).
/// - [Eq. 4.4] aggregates depth by a softmax alpha_k exp(z_k / gamma) with the background as a
///   sheet at the far plane. Against a background at depth t_bg a triangle then stays opaque up to
///   w sqrt((t_bg - t) / gamma) beyond its edges: every outline seen against the environment grows
///   by that (measured: docs/experiments/2026-11-26-regularized.md). Composition grows none. Its
///   cost: where two surfaces cross, the order of the two terms swaps, and that discontinuity (an
///   intersection curve) is not regularised.
///
/// Candidates: triangles with alpha > e^-kRegularizationCut, i.e. crossings within reach() =
/// w sqrt(kCut) of the triangle in its plane (the bound the candidate query grows its boxes by,
/// NearTriangleQuery); one left out would change no weight by more than that factor. The plane of
/// the triangle a ray leaves and planes crossed within a relative distance of its origin
/// (kRayOffsetRelative times the coordinate magnitude, as offset_ray_origin) are not candidates:
/// the ray's own surface.

#include "qsil/dual.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/surface_interaction.h"
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace qsil {

/// Candidates have alpha > e^-kRegularizationCut (see the file comment).
inline constexpr double kRegularizationCut = 40.0;

/// The parameters of regularised visibility (file comment), in scene units. width = 0: off.
struct Regularization {
  double width = 0;  ///< w: alpha = exp(-delta^2 / w^2) at in-plane distance delta outside a triangle
  bool enabled() const { return width > 0; }
  /// The largest in-plane distance outside a triangle at which it is a candidate: w sqrt(kCut).
  double reach() const { return width * std::sqrt(kRegularizationCut); }
  /// The parameters for `scene` from a width relative to its bounding-box diagonal D (w =
  /// width_rel D), computed once from the scene as given, so that displaced copies (finite
  /// differences) use the same number. Throws qsil::Error when width_rel is not positive and
  /// finite, or the scene has no extent.
  static Regularization for_scene(const Scene& scene, double width_rel);
};

/// One triangle a ray sees (detached values).
struct SoftCandidate {
  int shape = -1, triangle = -1;
  double t = 0;              ///< where the ray crosses the triangle's plane
  double log_alpha = 0;      ///< log alpha (0 inside)
  double log_transmit = 0;   ///< log (1 - alpha) (-inf inside)
  bool inside = false;       ///< the crossing lies on the triangle (alpha = 1)
  double cos = 0;            ///< unit geometric normal . ray direction
  unsigned edges = 7;        ///< the edges it blurs beyond (signed_squared_distance)
};

/// What a ray sees: its candidates sorted by t (none behind one crossed inside), and the detached
/// weights W_k of its terms and W_bg of the background (file comment).
struct SoftRay {
  std::vector<SoftCandidate> candidates;
  std::vector<double> weights;
  double background = 1;
};

/// f(z) over T from its value f and derivative df at value(z) (the chain rule by hand, for
/// functions Eigen's AutoDiffScalar lacks).
template <class T>
T chain(const T& z, double f, double df) {
  if constexpr (std::is_same_v<T, double>) {
    (void)z;
    (void)df;
    return f;
  } else {
    return T(f, z.derivatives() * df);
  }
}

/// sign(delta) delta^2 of point x in the plane of triangle (v0, v1, v2) with barycentrics b1, b2
/// of v1, v2 (Quinn Eq. 4.1's signed distance, squared so that it is smooth where delta = 0):
/// inside, the squared distance to the nearest edge; outside, minus the squared distance to the
/// nearest point of the edges in `edges` (bit i: the edge from vertex i to vertex i + 1 mod 3;
/// all three: the triangle), -inf when `edges` is 0. The opacity uses its negative part only.
template <class T>
T signed_squared_distance(const Vec3T<T>& x, const Vec3T<T>& v0, const Vec3T<T>& v1, const Vec3T<T>& v2,
                          const T& b1, const T& b2, unsigned edges = 7) {
  const bool inside = value(b1) >= 0 && value(b2) >= 0 && 1.0 - value(b1) - value(b2) >= 0;
  const Vec3T<T>* v[3] = {&v0, &v1, &v2};
  T best = T(kInf);
  for (int i = 0; i < 3; ++i) {
    if (!inside && !(edges & (1u << i))) continue;
    const Vec3T<T>& a = *v[i];
    const Vec3T<T> e = *v[(i + 1) % 3] - a;
    const T ee = e.squaredNorm();
    if (!(value(ee) > 0)) continue;
    T u = (x - a).dot(e) / ee;
    if (value(u) < 0) u = T(0.0);
    if (value(u) > 1) u = T(1.0);
    const T d2 = (x - a - e * u).squaredNorm();
    if (value(d2) < value(best)) best = d2;
  }
  return inside ? best : T(-best);
}

/// What regularised visibility needs of a scene, built once per scene (and per displaced copy):
/// the candidate query (NearTriangleQuery, grown by reach()) and, per triangle, which of its
/// edges bound its mesh (a mesh edge of one triangle; bit i: from vertex i to vertex i + 1).
class SoftScene {
 public:
  /// Throws qsil::Error as NearTriangleQuery does.
  SoftScene(const Scene& scene, const Regularization& reg);
  const NearTriangleQuery& query() const { return query_; }
  const Regularization& regularization() const { return reg_; }
  unsigned boundary_edges(int shape, int triangle) const { return boundary_[size_t(shape)][size_t(triangle)]; }

 private:
  Regularization reg_;
  NearTriangleQuery query_;
  std::vector<std::vector<uint8_t>> boundary_;
};

/// The candidates of the ray o + t d (t in (tmin, tmax)) among the triangles `query` returns,
/// except triangle (skip_shape, skip_triangle) (the one the ray leaves; -1: none), in doubles
/// from the scene's positions, with their weights; tmin: the relative distance of the file
/// comment, or 0. With `tracer` (the scene's; may be null), the ray's hard first hit, confirmed in
/// double, bounds how far along it candidates are looked for: nothing behind a triangle crossed
/// inside is seen. Sliver rays (leaves_below, path_tracer.h) are not let through back faces, unlike
/// path_tracer.h's (docs/design-notes.md "Regularised visibility": measured, left open).
void find_soft_candidates(const Scene& scene, const RayTracer* tracer, const SoftScene& soft, const Vec3& o,
                          const Vec3& d, double tmin, double tmax, int skip_shape, int skip_triangle, SoftRay& out);

/// The relative distance below which a plane crossing belongs to the ray's own surface: the
/// offset of offset_ray_origin for a ray leaving `si` (0 for a camera ray: pass no interaction).
double soft_ray_tmin(double scale, const Vec3& p, const Vec3& local_origin);

/// log alpha and log (1 - alpha) of candidate c over the view's scalar type, with the crossing
/// recomputed from the (moving) vertices and origin `o` along the fixed direction d. Inside
/// (c.inside): 0 and -inf, constant.
template <class View>
std::pair<typename View::Real, typename View::Real> soft_opacity(const View& view, const Regularization& reg,
                                                                 const SoftCandidate& c,
                                                                 const Vec3T<typename View::Real>& o, const Vec3& d) {
  using T = typename View::Real;
  if (c.inside) return {T(0.0), T(-kInf)};
  Hit h;
  h.shape = c.shape;
  h.triangle = c.triangle;
  h.t = c.t;
  const SurfaceInteraction<T> si = make_interaction(view, h, o, d);
  if constexpr (!std::is_same_v<T, double>)
    if (si.constant) return {T(c.log_alpha), T(c.log_transmit)};
  const Eigen::Vector3i& tri = view.scene->shapes[size_t(c.shape)].mesh.triangles[size_t(c.triangle)];
  // u2 = delta^2 / w^2 >= 0 outside; log alpha = -u2; d/du2 log(1 - e^-u2) = 1 / expm1(u2).
  const T u2 = -signed_squared_distance<T>(si.p, view.position(c.shape, tri[0]), view.position(c.shape, tri[1]),
                                           view.position(c.shape, tri[2]), si.b1, si.b2, c.edges) /
               T(reg.width * reg.width);
  // Values from the detached candidate (u2 = -log alpha > 0 there), derivatives from u2.
  // (u2 at least the smallest normal double: 1 / expm1 stays finite, and 0 x that is 0.)
  return {chain<T>(u2, c.log_alpha, -1.0),
          chain<T>(u2, c.log_transmit, 1.0 / std::expm1(std::max(-c.log_alpha, std::numeric_limits<double>::min())))};
}

/// The weights of a ray's terms over the view's scalar type (W_k for candidate k, W_bg for the
/// background; file comment). Every candidate in front of a term moves its weight; a view
/// without derivatives takes the detached values.
template <class T>
struct SoftWeights {
  std::vector<T> w;
  T background = T(0.0);
  /// W_k(theta) / W_k for term k (-1: the background): the weight of a term sampled with
  /// probability W_k (value 1, derivative d log W_k).
  T ratio(int k) const {
    const T& x = k < 0 ? background : w[size_t(k)];
    return x / T(value(x));
  }
};

template <class View>
void soft_weights(const View& view, const Regularization& reg, const SoftRay& ray, const Vec3T<typename View::Real>& o,
                  const Vec3& d, SoftWeights<typename View::Real>& out) {
  using T = typename View::Real;
  const size_t n = ray.candidates.size();
  out.w.resize(n);
  if constexpr (std::is_same_v<T, double>) {
    for (size_t k = 0; k < n; ++k) out.w[k] = ray.weights[k];
    out.background = ray.background;
  } else {
    using std::exp;
    T log_front = T(0.0);  // sum of log (1 - alpha_j) over the terms in front
    bool covered = false;
    for (size_t k = 0; k < n; ++k) {
      const auto [la, lt] = soft_opacity(view, reg, ray.candidates[k], o, d);
      out.w[k] = exp(la + log_front);
      if (ray.candidates[k].inside) {
        covered = true;
        break;  // the last term
      }
      log_front += lt;
    }
    out.background = covered ? T(0.0) : T(exp(log_front));
  }
}

/// The index of the term of `ray` that u in [0, 1) picks with probability W (-1: the background).
int pick_soft_candidate(const SoftRay& ray, double u);

}  // namespace qsil
