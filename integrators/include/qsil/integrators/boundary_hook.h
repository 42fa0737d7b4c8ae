#pragma once
/// @file boundary_hook.h
/// The vertex hook of trace_path with which forward mode adds the secondary boundary term to a
/// path's derivative (reverse mode's hook is in integrators/reverse.cpp).

#include "qsil/integrators/boundary_term.h"
#include "qsil/integrators/edge_jump.h"

namespace qsil {

/// The vertex hook of trace_path that adds the secondary boundary term (DualView<N> paths only).
template <int N>
struct BoundaryHook : BoundaryHookBase {
  void operator()(const SurfaceInteraction<Dual<N>>& si, const ShadingPoint<Dual<N>>& sp, const Vec3& wo_local,
                  const ColorT<Dual<N>>& beta, int seg, Sampler&, PathStats& stats, ColorT<Dual<N>>& L) const {
    // ---- dp/dtheta: does the shading point move?
    Eigen::Matrix<double, 3, N> dp;
    for (int i = 0; i < 3; ++i) dp.row(i) = si.p[i].derivatives().transpose();
    edgetree::SilhouetteQuery q = boundary_query(*boundary_ctx, si, sp, wo_local, scratch);
    q.eligible = !dp.isZero(0.0) ? &boundary_ctx->all : &boundary_ctx->moving;
    q.velocities = boundary_ctx->velocities;
    q.dp.setZero();
    q.dp.template leftCols<N>() = dp;
    q.velocity_scale = boundary_ctx->velocity_scale;
    Eigen::Matrix<double, 1, N> J;  // of the sample being evaluated
    for_each_boundary_sample(
        *ctx, *boundary_ctx, vertex(si, sp, q, wo_local, beta, seg), *sampler, stats,
        [&](const edgetree::Edge& e, double t, const Vec3& g) {
          J = edge_point_jacobian<N>(*boundary_ctx->velocities, e, t, g, dp);
          return !J.isZero(0.0);
        },
        [&](const edgetree::Edge&, double, const Color& weight, const Vec3&) {
          for (int c = 0; c < 3; ++c) L[c] += Dual<N>(0.0, (weight[c] * J).transpose());
        });
  }
};


}  // namespace qsil
