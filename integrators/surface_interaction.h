#pragma once
/// @file surface_interaction.h
/// The differentiable hit point of a fixed-direction ray (docs/architecture.md §4): Embree chooses the
/// triangle; the distance t, the barycentrics, the point and the normals are recomputed over the
/// view's scalar type from the (moving) vertices and the (moving) ray origin. The direction is a
/// detached double: directions are fixed in qsil's parametrization.

#include "qsil/dual.h"
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"

namespace qsil {

/// A surface point over scalar type T.
template <class T> struct SurfaceInteraction {
  int shape = -1, triangle = -1;
  T t;              ///< distance from the ray origin along the unit direction
  T b1, b2;         ///< barycentrics of vertices 1 and 2
  Vec3T<T> p;       ///< world position
  Vec3T<T> ng;      ///< unit geometric normal (counter-clockwise winding = outward)
  Vec3T<T> ns;      ///< unit shading normal (interpolated vertex normals, or ng for face_normals)
  double scale = 0; ///< largest absolute vertex coordinate of the triangle (ray offsets)
};

/// Ray-triangle intersection (Moller-Trumbore 1997) over scalar T with origin o (T) and fixed unit
/// direction d, for the triangle Embree reported in `hit`. Works outside the triangle too (the
/// barycentrics are then extrapolated): Embree decided which triangle is hit. With hit.exact the
/// point is interpolated from hit.u, hit.v instead (a known point; no ray-plane intersection).
template <class View>
SurfaceInteraction<typename View::Real> make_interaction(const View& view, const Hit& hit,
                                                         const Vec3T<typename View::Real>& o, const Vec3& d) {
  using T = typename View::Real;
  SurfaceInteraction<T> si;
  si.shape = hit.shape;
  si.triangle = hit.triangle;
  const Shape& shape = view.scene->shapes[hit.shape];
  const Eigen::Vector3i& tri = shape.mesh.triangles[hit.triangle];
  const Vec3T<T> v0 = view.position(hit.shape, tri[0]);
  const Vec3T<T> v1 = view.position(hit.shape, tri[1]);
  const Vec3T<T> v2 = view.position(hit.shape, tri[2]);
  const Vec3T<T> e1 = v1 - v0, e2 = v2 - v0;
  const Vec3T<T> dT = lift<T>(d);
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
  si.scale = std::max({P[tri[0]].cwiseAbs().maxCoeff(), P[tri[1]].cwiseAbs().maxCoeff(),
                       P[tri[2]].cwiseAbs().maxCoeff()});
  return si;
}

}  // namespace qsil
