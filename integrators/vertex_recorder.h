#pragma once
/// @file vertex_recorder.h
/// The vertex hooks that record a retraced sample's path and its secondary boundary term's largest
/// edge point (qsil/integrators/sample_trace.h).

#include "qsil/dual.h"
#include "qsil/integrators/boundary_hook.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/integrators/sample_trace.h"
#include "qsil/integrators/surface_interaction.h"

#include <utility>
#include <vector>

namespace qsil {

/// The vertex hook of trace_path that records each vertex into `trace` (forward mode, derivative
/// `param` of duals of size N). Called at every vertex that may still scatter; the derivative L
/// has gathered at each call closes the previous vertex's `added` (finish() closes the last and
/// sets every vertex's `arises`; jacobian() adds an attached camera ray's Jacobian term).
/// One recorder per traced sample.
template <int N>
struct VertexRecorder {
  SampleTrace* trace;
  int param;
  mutable double last = 0;  ///< channel-mean derivative of L at the previous call
  /// What `arises` needs of each recorded vertex, per channel (derivatives for `param`).
  struct Reached {
    Color beta, dbeta;  ///< the throughput reaching the vertex and its derivative
    Color L, dL;        ///< L when the vertex was reached and its derivative
  };
  mutable std::vector<Reached> at = {};

  /// The value and the derivative for `param` of a colour over duals.
  static std::pair<Color, Color> split(const ColorT<Dual<N>>& c, int k) {
    Color v, d;
    for (int i = 0; i < 3; ++i) {
      v[i] = c[i].value();
      d[i] = c[i].derivatives()[k];
    }
    return {v, d};
  }

  static double mean_derivative(const ColorT<Dual<N>>& L, int k) {
    return (L[0].derivatives()[k] + L[1].derivatives()[k] + L[2].derivatives()[k]) / 3.0;
  }

  void operator()(const SurfaceInteraction<Dual<N>>& si, const ShadingPoint<Dual<N>>& sp, const Vec3& wo_local,
                  const ColorT<Dual<N>>& beta, int seg, Sampler& /*sampler*/, PathStats& /*stats*/,
                  ColorT<Dual<N>>& L) const {
    const double now = mean_derivative(L, param);
    if (trace->vertices.empty())
      trace->camera_emission = now;
    else
      trace->vertices.back().added = now - last;
    last = now;
    const auto [b, db] = split(beta, param);
    const auto [l, dl] = split(L, param);
    at.push_back({b, db, l, dl});
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

  /// Closes the last vertex with the path's final derivative `L` (trace_path's result, before any
  /// camera Jacobian) and splits the interior term by where it arises (VertexTrace::arises): vertex
  /// k collects A_k (value a_k, derivative a'_k, per channel) with throughput b_k, so
  /// a'_k = (b'_k / b_k) a_k + [the rest, k's own part], and b'_k / b_k = g_k is the sum of the
  /// log-derivatives g_{i+1} - g_i that the earlier vertices' factors add (g_1 the first
  /// throughput's); vertex i then takes its own part plus (g_{i+1} - g_i) times sum_{k > i} a_k.
  /// The split telescopes to the sum of the a'_k for any g, so the parts add up to the interior
  /// term exactly; a channel whose throughput is 0 gives g = 0 there (its part stays its own).
  void finish(const ColorT<Dual<N>>& L) const {
    const double now = mean_derivative(L, param);
    if (trace->vertices.empty())
      trace->camera_emission = now;
    else
      trace->vertices.back().added = now - last;
    trace->interior = now;
    const size_t n = at.size();
    const auto [l_end, dl_end] = split(L, param);
    // Per vertex k, per channel: a_k, a'_k (what it collects) and g_k (its throughput's log-derivative).
    std::vector<Color> a(n), da(n), g(n);
    for (size_t k = 0; k < n; ++k) {
      a[k] = (k + 1 < n ? at[k + 1].L : l_end) - at[k].L;
      da[k] = (k + 1 < n ? at[k + 1].dL : dl_end) - at[k].dL;
      g[k] = (at[k].beta != 0).select(at[k].dbeta / at[k].beta, 0.0);
    }
    Color later = Color::Zero();  // sum of a_j over j > k
    for (size_t k = n; k-- > 0;) {
      Color part = da[k] - g[k] * a[k];
      if (k + 1 < n) part += (g[k + 1] - g[k]) * later;
      later += a[k];
      if (k == 0) part += g[0] * later;
      trace->vertices[k].arises = part.mean();
    }
  }

  /// After finish(): the attached camera ray's Jacobian term, the difference between `L` (after
  /// AttachedCameraRay::apply_jacobian) and the L finish() was given, into
  /// SampleTrace::camera_jacobian, the first vertex's `arises` and the interior term.
  void jacobian(const ColorT<Dual<N>>& L) const {
    const double now = mean_derivative(L, param);
    trace->camera_jacobian = now - trace->interior;
    if (!trace->vertices.empty()) trace->vertices.front().arises += trace->camera_jacobian;
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
