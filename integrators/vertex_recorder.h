#pragma once
/// @file vertex_recorder.h
/// The vertex hooks that record a retraced sample's path and its secondary boundary term's largest
/// edge point (qsil/integrators/sample_trace.h).

#include "qsil/dual.h"
#include "qsil/integrators/boundary_hook.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/integrators/sample_trace.h"
#include "qsil/integrators/surface_interaction.h"

namespace qsil {

/// The vertex hook of trace_path that records each vertex into `trace` (forward mode, derivative
/// `param` of duals of size N). Called at every vertex that may still scatter; the derivative L
/// has gathered at each call closes the previous vertex's `added` (finish() closes the last).
template <int N>
struct VertexRecorder {
  SampleTrace* trace;
  int param;
  mutable double last = 0;  ///< channel-mean derivative of L at the previous call

  static double mean_derivative(const ColorT<Dual<N>>& L, int k) {
    return (L[0].derivatives()[k] + L[1].derivatives()[k] + L[2].derivatives()[k]) / 3.0;
  }

  void operator()(const SurfaceInteraction<Dual<N>>& si, const ShadingPoint<Dual<N>>& sp, const Vec3& wo_local,
                  const ColorT<Dual<N>>& /*beta*/, int seg, Sampler& /*sampler*/, PathStats& /*stats*/,
                  ColorT<Dual<N>>& L) const {
    const double now = mean_derivative(L, param);
    if (trace->vertices.empty())
      trace->camera_emission = now;
    else
      trace->vertices.back().added = now - last;
    last = now;
    VertexTrace v;
    v.segments = seg;
    v.shape = si.shape;
    v.triangle = si.triangle;
    const Vec3 wo_world = sp.frame_value.to_world(wo_local);
    v.cos_geometric = std::abs(value(si.ng).dot(wo_world));
    v.cos_shading = wo_local.z();
    v.dt = si.t.derivatives()[param];
    Vec3 dp, dns;
    for (int i = 0; i < 3; ++i) {
      dp[i] = si.p[i].derivatives()[param];
      dns[i] = sp.frame.n[i].derivatives()[param];
    }
    v.dp = dp.norm();
    v.dns = dns.norm();
    trace->vertices.push_back(v);
  }

  /// Closes the last vertex with the path's final derivative `L` (trace_path's result).
  void finish(const ColorT<Dual<N>>& L) const {
    const double now = mean_derivative(L, param);
    if (trace->vertices.empty())
      trace->camera_emission = now;
    else
      trace->vertices.back().added = now - last;
    trace->interior = now;
  }
};

/// The vertex hook of trace_path that evaluates the secondary boundary term as BoundaryHook does
/// (the same query, stream and traversals, so the same edge points) but adds nothing to L: it
/// records into `trace->boundary` the count and sum of the edge points' contributions to the
/// derivative `param` and the factors of the largest (BoundaryPointTrace).
template <int N>
struct BoundaryPointRecorder : BoundaryHookBase {
  SampleTrace* trace;
  int param;

  void operator()(const SurfaceInteraction<Dual<N>>& si, const ShadingPoint<Dual<N>>& sp, const Vec3& wo_local,
                  const ColorT<Dual<N>>& beta, int seg, Sampler&, PathStats& stats, ColorT<Dual<N>>&) const {
    Eigen::Matrix<double, 3, N> dp;
    const edgetree::SilhouetteQuery q = forward_boundary_query<N>(*this, si, sp, wo_local, dp);
    Eigen::Matrix<double, 1, N> J;
    BoundaryPointTrace& b = trace->boundary;
    for_each_boundary_sample(
        *ctx, *boundary_ctx, vertex(si, sp, q, wo_local, beta, seg), *sampler, stats, forward_accept<N>(*this, dp, J),
        [&](const edgetree::Edge& e, double t, const Color& weight, const Vec3&, const EdgePointFactors& f) {
          const double added = weight.mean() * J[param];
          ++b.points;
          b.total += added;
          if (b.points > 1 && !(std::abs(added) > std::abs(b.added))) return;
          const Vec3 x = e.p0 + t * (e.p1 - e.p0);
          const Vec3 to = x - q.p;
          b.segments = seg;
          b.shape = e.shape;
          b.kind = e.crossing ? 3 : e.smooth_crease ? 2 : e.crease ? 1 : 0;
          b.pdf = f.pdf;
          b.rate = f.rate;
          b.jump = f.jump.abs().mean();
          b.bsdf = f.bsdf.abs().mean();
          b.throughput = value(beta).abs().mean();
          b.jacobian = J[param];
          b.distance = to.norm();
          b.edge_length = (e.p1 - e.p0).norm();
          b.sin_view = b.distance > 0 && b.edge_length > 0
                           ? to.normalized().cross((e.p1 - e.p0).normalized()).norm()
                           : 0.0;
          b.added = added;
        });
  }
};

/// Two vertex hooks called in turn at every vertex (a VertexRecorder and a BoundaryPointRecorder).
template <class A, class B>
struct BothHooks {
  const A& a;
  const B& b;
  template <class... Args>
  void operator()(Args&&... args) const {
    a(args...);
    b(args...);
  }
};

}  // namespace qsil
