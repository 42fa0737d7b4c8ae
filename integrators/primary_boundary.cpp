/// @file primary_boundary.cpp
/// See primary_boundary.h.

#include "primary_boundary.h"

#include "pixel_loop.h"
#include "qsil/edgetree/mesh_edges.h"
#include "qsil/error.h"
#include "qsil/integrators/attached_camera.h"
#include "qsil/integrators/boundary_term.h"
#include "sample_chunks.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace qsil {

namespace {

/// Where a primary sample lies on the film (pixels), its weight W per_sample / pdf without the
/// jump, and the jump's two sides (PrimaryEdges::attached) or null.
struct PrimaryPoint {
  Vec2 film;
  double scale = 0;
  const EdgeSides* sides = nullptr;
};

/// Clips the camera-space segment c0 + t (c1 - c0), t in [ta, tb], to the half space n.c >= d.
bool clip(const Vec3& c0, const Vec3& c1, const Vec3& n, double d, double& ta, double& tb) {
  const double f0 = n.dot(c0) - d, f1 = n.dot(c1) - d;
  if (f0 < 0 && f1 < 0) return false;
  if (f0 >= 0 && f1 >= 0) return true;
  const double tc = f0 / (f0 - f1);  // the crossing
  if (f0 < 0)
    ta = std::max(ta, tc);
  else
    tb = std::min(tb, tc);
  return ta < tb;
}

/// Draws `count` primary edge samples of chunk `chunk` from its stream (stream::kPrimary) and
/// evaluates them: `accept(edge, t, g)` sees the Jacobian's linear form g (edge_jump_with) before
/// any ray; `emit(px, py, edge, t, weight, g, point)` receives each contributing sample, weight =
/// jump W per_sample / pdf (so the pixel's derivative gains weight (g . v_t)), and `point`: where
/// it lies on the film, W per_sample / pdf, and the jump's two sides (PrimaryEdges::attached only;
/// else null). Shared by forward mode (add_primary_boundary) and reverse mode
/// (for_each_primary_sample).
template <class Accept, class Emit>
void sample_chunk(const PathContext& ctx, const PrimaryEdges& primary, long long count, double per_sample,
                  uint64_t seed, long long chunk, PathStats& stats, Accept&& accept, Emit&& emit) {
  const Camera& cam = ctx.scene->camera;
  const Vec2 tanf = cam.tan_half_fov();
  const double fx = cam.width / (2.0 * tanf.x()), fy = cam.height / (2.0 * tanf.y());
  const Vec3 o = cam.origin();
  const Vec3 forward = cam.to_world.block<3, 1>(0, 2).normalized();
  const std::vector<double>& cdf = primary.cdf;
  Sampler sampler(seed, uint64_t(chunk), 0, stream::kPrimary);
  for (long long i = 0; i < count; ++i) {
    ++stats.boundary_traversals;
    // ---- A piece of an edge by its weight (projected length, less for creases and hidden
    // pieces), a point uniformly along its projected part.
    const double u = sampler.next() * cdf.back();
    const size_t j =
        std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1, primary.pieces.size() - 1);
    const PrimaryPiece& piece = primary.pieces[j];
    const PrimaryEdge& pe = primary.edges[size_t(piece.edge)];
    const double s = piece.s0 + sampler.next() * (piece.s1 - piece.s0);
    const double tp = pe.tp_at(s);  // perspective-correct
    const double t = pe.ta + tp * (pe.tb - pe.ta);
    const double dsdt = pe.za * pe.zb / std::pow((1 - tp) * pe.za + tp * pe.zb, 2);  // ds/dt'
    const double pdf = (piece.weight / cdf.back()) / (piece.s1 - piece.s0) * dsdt / (pe.tb - pe.ta);
    const Vec2 film = pe.a + s * (pe.b - pe.a);
    const int px = std::clamp(int(film.x()), 0, cam.width - 1), py = std::clamp(int(film.y()), 0, cam.height - 1);
    // ---- W(w) = f_x f_y / cos^3: pixels^2 per steradian of the box-filtered pixel.
    const Vec3 w = (pe.edge->p0 + t * (pe.edge->p1 - pe.edge->p0) - o).normalized();
    const double cos_theta = w.dot(forward);
    if (!(cos_theta > 0) || !(pdf > 0)) {
      ++stats.boundary_zero;
      continue;
    }
    const double W = fx * fy / (cos_theta * cos_theta * cos_theta);
    Vec3 g;
    EdgeSides sides;
    // Seen from the camera centre: no surface to offset from or pass below, no own face, depth 0.
    const EdgeJumpInputs in{.edge = *pe.edge,
                            .t = t,
                            .p = o,
                            .vis_origin = o,
                            .through_back_faces = false,
                            .own = OwnFace{},
                            .segments = 0,
                            .sides = primary.attached ? &sides : nullptr};
    const std::optional<Color> jump = edge_jump_with(ctx, in, sampler, stats, [&](const Vec3& gv) {
      g = gv;
      return accept(*pe.edge, t, gv);
    });
    const bool sides_differ = primary.attached && sides.count == 2;
    if (!jump || ((*jump == 0).all() && !sides_differ)) {
      ++stats.boundary_zero;
      continue;
    }
    const PrimaryPoint point{film, W * per_sample / pdf, primary.attached ? &sides : nullptr};
    emit(px, py, *pe.edge, t, Color(*jump * point.scale), g, point);
  }
}

/// The attached form's flux through a primary discontinuity (attached_camera.h), per parameter
/// and colour (for_each_attached_side with the velocities of `vel`).
template <int N>
Eigen::Matrix<double, 3, N> attached_flux(const Scene& scene, const SceneVelocities& vel,
                                          const CameraAttachment& attachment, const EdgeSides& sides, const Vec3& g,
                                          const Vec3& xe, const Vec2& film, int px, int py) {
  Eigen::Matrix<double, 3, N> flux = Eigen::Matrix<double, 3, N>::Zero();
  for_each_attached_side(
      scene, attachment, sides, xe, film, px, py, [&](const EdgeSides::Side& side, double k, const Color& L) {
        if (!vel.moving[size_t(side.hit.shape)]) return;
        const Eigen::Matrix<double, 1, N> gv =
            g.transpose() * material_velocity<N>(vel, scene, side.hit.shape, side.hit.triangle, side.hit.u, side.hit.v);
        flux -= k * L.matrix() * gv;
      });
  return flux;
}

/// Forward mode: the splats of one chunk, J[k] = g . (velocity of the edge point) (the camera
/// does not move), plus the attached form's flux (PrimaryEdges::attached).
template <int N>
void run_chunk(const PathContext& ctx, const SceneVelocities& vel, const PrimaryEdges& primary, long long count,
               double per_sample, uint64_t seed, long long chunk, std::vector<FilmSplat>& out,
               PathStats& stats) {
  const int K = vel.num_params;
  const FilmLayout layout(K);
  Eigen::Matrix<double, 1, N> J;
  const Eigen::Matrix<double, 3, N> dp = Eigen::Matrix<double, 3, N>::Zero();  // the camera does not move
  // Attached camera hits: a static edge (J = 0) can bound an attached shape's flux.
  auto accept = [&](const edgetree::Edge& e, double t, const Vec3& g) {
    J = edge_point_jacobian<N>(vel, e, t, g, dp);
    return primary.attached || !J.isZero(0.0);
  };
  auto emit = [&](int px, int py, const edgetree::Edge& e, double t, const Color& weight, const Vec3& g,
                  const PrimaryPoint& point) {
    Eigen::Matrix<double, 3, N> flux = Eigen::Matrix<double, 3, N>::Zero();
    if (point.sides)
      flux = point.scale * attached_flux<N>(*ctx.scene, vel, primary.attachment, *point.sides, g,
                                            Vec3(e.p0 + t * (e.p1 - e.p0)), point.film, px, py);
    for (int k = 0; k < K; ++k) {
      for (int c = 0; c < 3; ++c) out.push_back({px, py, layout.derivative(k, c), weight[c] * J[k] + flux(c, k)});
      out.push_back({px, py, layout.derivative_mean(k), weight.mean() * J[k] + flux.col(k).mean()});
    }
  };
  sample_chunk(ctx, primary, count, per_sample, seed, chunk, stats, accept, emit);
}

/// The chunk plan of the primary term (see add_primary_boundary for the numbering).
ChunkPlan primary_plan(const Camera& cam, const PrimaryEdges& primary, double ratio, int first_sample, int spp,
                       int part, int parts) {
  return ChunkPlan(primary_samples_per_index(cam.width, cam.height, ratio), primary.empty(), first_sample, spp, part,
                   parts, "primary boundary term", "--sppp");
}

}  // namespace

namespace {

/// Whether the point of `pe` at s is visible from o: the boundary term's own visibility test
/// (point_visible, ignoring the edge's faces).
bool primary_point_visible(const RayTracer& tracer, const Vec3& o, const PrimaryEdge& pe, double s) {
  return point_visible(tracer, o, pe.point_at(s), edge_faces(*pe.edge, false));
}

}  // namespace

long long primary_samples_per_index(int width, int height, double ratio) {
  if (!(ratio > 0 && ratio <= 1024))
    throw Error("primary samples per pixel sample must be in (0, 1024] (got " + std::to_string(ratio) + ")");
  constexpr long long kChunk = ChunkPlan::kChunkSize;
  const double n = std::ceil(ratio * double(width) * double(height) / double(kChunk));
  return std::max(1LL, (long long)n) * kChunk;
}

double PrimaryEdges::density(int edge, double s) const {
  if (edge < 0 || edge >= int(edges.size()) || cdf.empty() || !(cdf.back() > 0)) return 0.0;
  const PrimaryEdge& pe = edges[size_t(edge)];
  double d = 0;
  for (int k = pe.first_piece; k < pe.first_piece + pe.piece_count; ++k) {
    const PrimaryPiece& piece = pieces[size_t(k)];
    if (s >= piece.s0 && s <= piece.s1) d = std::max(d, piece.weight / (piece.s1 - piece.s0));
  }
  return d / cdf.back();
}

PrimaryEdges find_primary_edges(const Scene& scene, const edgetree::EdgeSet& edges, const std::vector<bool>& moving,
                                const RayTracer& tracer, double hidden_share, CameraHits hits) {
  QSIL_CHECK(hidden_share > 0 && hidden_share <= 1);
  const Camera& cam = scene.camera;
  const Vec3 o = cam.origin();
  const Vec2 tf = cam.tan_half_fov();
  PrimaryEdges out;
  out.attachment = camera_attachment(scene, moving, hits);
  out.attached = out.attachment.any();
  const bool attached = out.attached;
  std::vector<bool> fixed;  // per edge of out.edges: of a static shape
  // An index `moving` does not cover counts as moving (SilhouetteQuery::eligible's rule: never a
  // false reject).
  const auto moves = [&](int shape) { return shape >= int(moving.size()) || moving[size_t(shape)]; };
  // Silhouettes and boundary edges from o, and every crease of a flat-shaded shape (its two
  // faces both seen: the shading jumps across it).
  auto consider = [&](const edgetree::Edge& e) {
    // Moving shapes' edges (and crossing groups with a moving shape). Attached: static shapes'
    // silhouettes and boundary edges too.
    if (e.shape < 0) return;
    const bool is_static = !moves(e.shape);
    if (is_static && (!attached || e.crossing)) return;
    if (!edgetree::is_discontinuity(e, o)) return;
    if (is_static && e.crease && !edgetree::edge_is_silhouette(e, o)) return;
    const Vec3 c0 = cam.to_camera(e.p0), c1 = cam.to_camera(e.p1);
    PrimaryEdge pe;
    pe.edge = &e;
    // Near plane and the four side planes of the frustum (camera space).
    if (!clip(c0, c1, Vec3(0, 0, 1), cam.near_clip, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(-1, 0, tf.x()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(1, 0, tf.x()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(0, -1, tf.y()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(0, 1, tf.y()), 0, pe.ta, pe.tb)) return;
    pe.a = cam.project(e.p0 + pe.ta * (e.p1 - e.p0), &pe.za);
    pe.b = cam.project(e.p0 + pe.tb * (e.p1 - e.p0), &pe.zb);
    pe.length = (pe.b - pe.a).norm();
    pe.weight = pe.length * (e.crease ? std::max(e.angle, 1e-3) / kPi : 1.0);
    if (pe.weight > 0 && pe.za > 0 && pe.zb > 0) {
      out.edges.push_back(pe);
      fixed.push_back(is_static);
    }
  };
  for (const auto& e : edges.edges()) consider(e);
  for (const auto& e : edges.always_edges()) consider(e);
  // ---- Pieces and their visibility from the camera (in parallel: one task per edge; each edge's
  // pieces depend on it alone, so the result is the same for any thread count).
  std::vector<std::vector<PrimaryPiece>> per_edge(out.edges.size());
  tbb::parallel_for(size_t(0), out.edges.size(), [&](size_t i) {
    const PrimaryEdge& pe = out.edges[i];
    const int k = std::clamp(int(std::ceil(pe.length / kPrimaryPieceLength)), 1, kPrimaryMaxPieces);
    bool prev = primary_point_visible(tracer, o, pe, 0.0);
    // A static edge: does the ray through the point, past the edge, meet a moving shape?
    const auto moving_behind = [&](double s) {
      const Vec3 x = pe.point_at(s);
      const Hit h = tracer.intersect(o, (x - o).normalized(), kInf, edge_faces(*pe.edge, false));
      return h.valid() && moves(h.shape);
    };
    for (int j = 0; j < k; ++j) {
      const double s0 = double(j) / k, s1 = j + 1 == k ? 1.0 : double(j + 1) / k;
      const bool mid = primary_point_visible(tracer, o, pe, 0.5 * (s0 + s1));
      const bool end = primary_point_visible(tracer, o, pe, s1);
      bool visible = prev || mid || end;
      if (fixed[i] && visible) visible = moving_behind(s0) || moving_behind(0.5 * (s0 + s1)) || moving_behind(s1);
      per_edge[i].push_back({int(i), s0, s1, pe.weight * (s1 - s0) * (visible ? 1.0 : hidden_share), visible});
      prev = end;
    }
  });
  out.cdf.assign(1, 0.0);
  out.static_edges = int(std::count(fixed.begin(), fixed.end(), true));
  for (size_t i = 0; i < out.edges.size(); ++i) {
    out.edges[i].first_piece = int(out.pieces.size());
    out.edges[i].piece_count = int(per_edge[i].size());
    for (const PrimaryPiece& piece : per_edge[i]) {
      out.hidden_pieces += !piece.visible;
      out.pieces.push_back(piece);
      out.cdf.push_back(out.cdf.back() + piece.weight);
    }
  }
  return out;
}

void add_primary_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                          const PrimaryEdges& edges, double ratio, int first_sample, int spp, uint64_t seed,
                          int threads, PathStats& stats, int part, int parts, std::vector<FilmSplat>* deferred) {
  const ChunkPlan plan = primary_plan(ctx.scene->camera, edges, ratio, first_sample, spp, part, parts);
  std::vector<std::vector<FilmSplat>> splats{static_cast<size_t>(plan.chunks)};
  std::vector<PathStats> chunk_stats{static_cast<size_t>(plan.chunks)};
  const int K = velocities.num_params;
  plan.run(threads, [&](long long j, long long count, long long c) {
    with_dual_size(K, [&](auto n) {
      run_chunk<decltype(n)::value>(ctx, velocities, edges, count, plan.per_sample, seed, c, splats[size_t(j)],
                                    chunk_stats[size_t(j)]);
    });
  });
  merge_chunk_splats(splats, chunk_stats, film, stats, deferred);
}

void for_each_primary_sample(const PathContext& ctx, const PrimaryEdges& edges, double ratio, int first_sample, int spp,
                             uint64_t seed, int threads, PathStats& stats, const PrimarySampleFn& fn) {
  const ChunkPlan plan = primary_plan(ctx.scene->camera, edges, ratio, first_sample, spp, 0, 1);
  // In batches of chunks (a bounded buffer), each drawn in parallel and handed on in order.
  const long long batch = 64;
  std::vector<std::vector<PrimarySample>> samples{static_cast<size_t>(batch)};
  std::vector<PathStats> chunk_stats{static_cast<size_t>(batch)};
  for (long long j0 = 0; j0 < plan.chunks; j0 += batch) {
    const long long j1 = std::min(plan.chunks, j0 + batch);
    plan.run(
        threads,
        [&](long long j, long long count, long long c) {
          auto& out = samples[size_t(j - j0)];
          out.clear();
          chunk_stats[size_t(j - j0)] = PathStats{};
          sample_chunk(
              ctx, edges, count, plan.per_sample, seed, c, chunk_stats[size_t(j - j0)],
              [](const edgetree::Edge&, double, const Vec3&) { return true; },
              [&](int px, int py, const edgetree::Edge& e, double t, const Color& weight, const Vec3& g,
                  const PrimaryPoint& point) {
                PrimarySample sample;
                sample.px = px;
                sample.py = py;
                sample.edge = &e;
                sample.t = t;
                sample.weight = weight;
                sample.g = g;
                if (point.sides) {
                  sample.attached = true;
                  sample.sides = *point.sides;
                  sample.film = point.film;
                  sample.scale = point.scale;
                }
                out.push_back(sample);
              });
        },
        j0, j1);
    for (long long j = j0; j < j1; ++j) {
      for (const PrimarySample& s : samples[size_t(j - j0)]) fn(s);
      const PathStats& st = chunk_stats[size_t(j - j0)];
      stats.rays += st.rays;
      stats.boundary_traversals += st.boundary_traversals;
      stats.boundary_zero += st.boundary_zero;
    }
  }
}

}  // namespace qsil
