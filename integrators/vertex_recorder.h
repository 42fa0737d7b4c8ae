#pragma once
/// @file vertex_recorder.h
/// The vertex hook that records a retraced sample's path (qsil/integrators/sample_trace.h).

#include "qsil/dual.h"
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

}  // namespace qsil
