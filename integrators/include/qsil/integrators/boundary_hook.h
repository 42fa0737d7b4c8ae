#pragma once
/// @file boundary_hook.h
/// The vertex hook of trace_path with which forward mode adds the secondary boundary term to a
/// path's derivative (reverse mode's hook is in integrators/reverse.cpp).

#include "qsil/integrators/boundary_term.h"
#include "qsil/integrators/edge_jump.h"

namespace qsil {

/// Forward mode's boundary query at a path vertex (si, sp, viewer direction wo_local):
/// boundary_query with the scene's velocities and p's, dp = dp/dtheta (3 x N, world units per
/// unit of theta, from si.p's duals; written to `dp`), and the eligible edges: every shape's when
/// p moves (dp != 0: static edges move relative to it), else the moving shapes'.
template <int N>
edgetree::SilhouetteQuery forward_boundary_query(const BoundaryHookBase& hook, const SurfaceInteraction<Dual<N>>& si,
                                                 const ShadingPoint<Dual<N>>& sp, const Vec3& wo_local,
                                                 Eigen::Matrix<double, 3, N>& dp) {
  for (int i = 0; i < 3; ++i) dp.row(i) = si.p[i].derivatives().transpose();
  edgetree::SilhouetteQuery q = boundary_query(*hook.boundary_ctx, si, sp, wo_local, hook.scratch);
  q.eligible = !dp.isZero(0.0) ? &hook.boundary_ctx->all : &hook.boundary_ctx->moving;
  q.velocities = hook.boundary_ctx->velocities;
  q.dp.setZero();
  q.dp.template leftCols<N>() = dp;
  q.velocity_scale = hook.boundary_ctx->velocity_scale;
  return q;
}

/// Forward mode's accept test for for_each_boundary_sample at a vertex whose p moves by `dp`
/// (forward_boundary_query): computes J = g . (v_edge - dp) of the edge point (1 x N, per unit of
/// each parameter; edge_point_jacobian) into `J`, for the visit that follows, and accepts the point
/// iff J != 0 (one with J = 0 contributes nothing). BoundaryHook and the retrace's recorder
/// (vertex_recorder.h) share it, so that both weigh the same edge points alike.
template <int N>
auto forward_accept(const BoundaryHookBase& hook, const Eigen::Matrix<double, 3, N>& dp,
                    Eigen::Matrix<double, 1, N>& J) {
  return [&hook, &dp, &J](const edgetree::Edge& e, double t, const Vec3& g) {
    J = edge_point_jacobian<N>(*hook.boundary_ctx->velocities, e, t, g, dp);
    return !J.isZero(0.0);
  };
}

/// The vertex hook of trace_path that adds the secondary boundary term (DualView<N> paths only).
template <int N>
struct BoundaryHook : BoundaryHookBase {
  void operator()(const SurfaceInteraction<Dual<N>>& si, const ShadingPoint<Dual<N>>& sp, const Vec3& wo_local,
                  const ColorT<Dual<N>>& beta, int seg, Sampler&, PathStats& stats, ColorT<Dual<N>>& L) const {
    Eigen::Matrix<double, 3, N> dp;
    const edgetree::SilhouetteQuery q = forward_boundary_query<N>(*this, si, sp, wo_local, dp);
    Eigen::Matrix<double, 1, N> J;  // of the sample being evaluated
    for_each_boundary_sample(*ctx, *boundary_ctx, vertex(si, sp, q, wo_local, beta, seg), *sampler, stats,
                             forward_accept<N>(*this, dp, J),
                             [&](const edgetree::Edge&, double, const Color& weight, const Vec3&) {
                               for (int c = 0; c < 3; ++c) L[c] += Dual<N>(0.0, (weight[c] * J).transpose());
                             });
  }
};


}  // namespace qsil
