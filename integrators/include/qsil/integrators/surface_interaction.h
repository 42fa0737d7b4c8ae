#pragma once
/// @file surface_interaction.h
/// The differentiable hit point of a fixed-direction ray (docs/architecture.md §4): Embree chooses the
/// triangle; the distance t, the barycentrics, the point and the normals are recomputed over the
/// view's scalar type from the (moving) vertices and the (moving) ray origin. The direction is a
/// detached double (directions are fixed in qsil's parametrization), or, for warped-area sampling
/// (warp_field.h), a direction over the view's scalar type.

#include "qsil/dual.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"

#include <type_traits>

namespace qsil {

/// A surface point over scalar type T.
template <class T>
struct SurfaceInteraction {
  int shape = -1, triangle = -1;
  T t;               ///< distance from the ray origin along the unit direction
  T b1, b2;          ///< barycentrics of vertices 1 and 2
  Vec3T<T> p;        ///< world position
  Vec3T<T> ng;       ///< unit geometric normal (counter-clockwise winding = outward)
  Vec3T<T> ns;       ///< unit shading normal (interpolated vertex normals, or ng for face_normals)
  /// Largest absolute coordinate of the triangle's vertices relative to local_origin (ray offsets).
  double scale = 0;
  /// The ray tracer's local origin (RayTracer::local_origin): Embree's float error, and so every
  /// ray offset, is relative to coordinates measured from it, not from the world origin.
  Vec3 local_origin = Vec3::Zero();
  /// For a point given exactly (Hit::exact: a sampled edge point, on the triangle's boundary):
  /// the unit in-plane direction from p toward the triangle's centroid (or Hit::inward when
  /// given: a point of an intersection curve, the limit from the part of the triangle that the
  /// viewer sees, whose length may exceed 1), else zero. Rays leaving such a point start a
  /// relative offset inside the triangle (spawn_origin, times the length), so that what they see
  /// is the limit from the face's interior, not from the edge itself.
  Vec3 inward = Vec3::Zero();
  /// Every derivative is zero (a constant hit, lift_interaction): what depends on this point
  /// alone (its shading frame, BSDF values) may be computed in doubles and lifted. Code that
  /// gives p or the normals derivatives afterwards (a view's attach()) must clear it.
  bool constant = false;
};

/// `si` over scalar type T with zero derivatives (the same values), marked `constant`.
template <class T>
SurfaceInteraction<T> lift_interaction(const SurfaceInteraction<double>& si) {
  SurfaceInteraction<T> r;
  r.shape = si.shape;
  r.triangle = si.triangle;
  r.t = T(si.t);
  r.b1 = T(si.b1);
  r.b2 = T(si.b2);
  r.p = lift<T>(si.p);
  r.ng = lift<T>(si.ng);
  r.ns = lift<T>(si.ns);
  r.scale = si.scale;
  r.local_origin = si.local_origin;
  r.inward = si.inward;
  r.constant = true;
  return r;
}

/// Direction `d` over scalar type T: a fixed one (Vec3) lifted with zero derivatives, one that
/// moves with theta (Vec3T<T>, warped-area sampling) as it is.
template <class T, class Dir>
Vec3T<T> direction_over(const Dir& d) {
  if constexpr (std::is_same_v<Dir, Vec3>)
    return lift<T>(d);
  else
    return d;
}

/// Ray-triangle intersection (Moller-Trumbore 1997) over scalar T with origin o (T) and fixed unit
/// direction d, for the triangle Embree reported in `hit`. Works outside the triangle too (the
/// barycentrics are then extrapolated): Embree decided which triangle is hit. With hit.exact the
/// point is interpolated from hit.u, hit.v instead (a known point; no ray-plane intersection).
/// `local_origin`: the ray tracer's (RayTracer::local_origin), which the ray offsets are relative to.
///
/// A view that can tell a constant hit (`view.constant_hit(shape, o)`: a shape that does not move
/// and an origin with zero derivatives, DualView) gets it computed in doubles and lifted (zero
/// derivatives, the same values): the dual arithmetic would only carry zeros (docs/architecture.md
/// §4 "Constant interactions").
///
/// `Dir` is Vec3 (a fixed direction: qsil's parametrization) or Vec3T<View::Real> (a direction
/// that moves with theta: warped-area sampling's warped directions, warp_field.h; unit in value,
/// its derivatives tangent). A moving direction makes the hit constant only when its derivatives
/// are zero too.
template <class View, class Dir = Vec3>
SurfaceInteraction<typename View::Real> make_interaction(const View& view, const Hit& hit,
                                                         const Vec3T<typename View::Real>& o, const Dir& d,
                                                         const Vec3& local_origin = Vec3::Zero()) {
  using T = typename View::Real;
  constexpr bool fixed_direction = std::is_same_v<Dir, Vec3>;
  if constexpr (requires { view.constant_hit(hit.shape, o); }) {
    bool constant = view.constant_hit(hit.shape, o);
    if constexpr (!fixed_direction)
      for (int i = 0; i < 3 && constant; ++i) constant = (d[i].derivatives().array() == 0).all();
    if (constant)
      return lift_interaction<T>(make_interaction(PrimalView{view.scene}, hit, value(o), Vec3(value(d)), local_origin));
  }
  SurfaceInteraction<T> si;
  si.shape = hit.shape;
  si.triangle = hit.triangle;
  const Shape& shape = view.scene->shapes[hit.shape];
  const Eigen::Vector3i& tri = shape.mesh.triangles[hit.triangle];
  const Vec3T<T> v0 = view.position(hit.shape, tri[0]);
  const Vec3T<T> v1 = view.position(hit.shape, tri[1]);
  const Vec3T<T> v2 = view.position(hit.shape, tri[2]);
  const Vec3T<T> e1 = v1 - v0, e2 = v2 - v0;
  const Vec3T<T> dT = direction_over<T>(d);
  const Vec3T<T> pvec = dT.cross(e2);
  const T det = e1.dot(pvec);
  const T inv_det = T(1.0) / det;
  const Vec3T<T> tvec = o - v0;
  const Vec3T<T> qvec = tvec.cross(e1);
  if (hit.exact) {
    // A point known on the triangle: interpolate, and measure t along the ray.
    si.b1 = T(hit.u);
    si.b2 = T(hit.v);
    si.p = v0 + e1 * si.b1 + e2 * si.b2;
    si.t = (si.p - o).dot(dT);
    const Vec3 to_centroid = value(Vec3T<T>((v0 + v1 + v2) / T(3.0) - si.p));
    if (hit.inward != Vec3::Zero())
      si.inward = hit.inward;
    else if (to_centroid.norm() > 0)
      si.inward = to_centroid.normalized();
  } else {
    si.b1 = tvec.dot(pvec) * inv_det;
    si.b2 = dT.dot(qvec) * inv_det;
    si.t = e2.dot(qvec) * inv_det;
    si.p = o + dT * si.t;
  }
  const Vec3T<T> c = e1.cross(e2);
  using std::sqrt;
  si.ng = c / sqrt(c.squaredNorm());
  if (shape.face_normals || shape.mesh.normals.empty()) {
    si.ns = si.ng;
  } else {
    const T b0 = T(1.0) - si.b1 - si.b2;
    const Vec3T<T> n = view.normal(hit.shape, tri[0]) * b0 + view.normal(hit.shape, tri[1]) * si.b1 +
                       view.normal(hit.shape, tri[2]) * si.b2;
    const T len = sqrt(n.squaredNorm());
    si.ns = value(len) > 0 ? Vec3T<T>(n / len) : si.ng;
  }
  const auto& P = shape.mesh.positions;
  si.local_origin = local_origin;
  si.scale = std::max({(P[tri[0]] - local_origin).cwiseAbs().maxCoeff(), (P[tri[1]] - local_origin).cwiseAbs().maxCoeff(),
                       (P[tri[2]] - local_origin).cwiseAbs().maxCoeff()});
  return si;
}

/// Origin of a ray leaving surface interaction `si` toward unit direction `dir`: offset off the
/// surface along the geometric normal (offset_ray_origin), and for a point exactly on the
/// triangle's boundary also into the triangle by the same relative distance. Why the second
/// offset: the radiance leaving an edge point (a silhouette's foreground) is the limit from the
/// face's interior; from the edge point itself a sliver ray would slip past the edge where one
/// from inside the face meets the neighbouring face (docs/design-notes.md "Smooth shading").
template <class T>
Vec3 spawn_origin(const SurfaceInteraction<T>& si, const Vec3& dir) {
  const Vec3 p = value(si.p);
  Vec3 o = offset_ray_origin(p, value(si.ng), dir, si.scale, si.local_origin);
  if (si.inward != Vec3::Zero())
    o += kRayOffsetRelative * std::max(si.scale, (p - si.local_origin).cwiseAbs().maxCoeff()) * si.inward;
  return o;
}

}  // namespace qsil
