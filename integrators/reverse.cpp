/// @file reverse.cpp
/// Reverse mode (per-vertex gradients of a scalar loss); see qsil/integrators/reverse.h.

#include "qsil/integrators/reverse.h"

#include "attached_control.h"
#include "pixel_loop.h"
#include "qsil/error.h"
#include "qsil/fnv1a.h"
#include "qsil/integrators/attached_camera.h"
#include "qsil/integrators/boundary_term.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/vertex_normals.h"
#include "render_setup.h"

#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>
#include <type_traits>
#include <unordered_map>

namespace qsil {

namespace {

/// Chosen-shape hits that get derivative slots in one pass of a path.
constexpr int kHitsPerPass = 2;
/// Slots of one hit: its point p (3) and its shading normal ns (3). The geometric normal needs
/// none: the path tracer reads only its value (make_shading_point, offsets, leaves_below).
constexpr int kSlotsPerHit = 6;
constexpr int kSlots = kHitsPerPass * kSlotsPerHit;
using RDual = Dual<kSlots>;
/// The local Jacobian of a hit: its triangle's three vertex positions (9) and normals (9).
constexpr int kLocal = 18;
using LDual = Dual<kLocal>;
/// Where the first pass of a path whose camera hit is attached (attached_camera.h) puts the
/// camera direction's three slots: the second hit's, so that pass holds one hit (Tape::capacity).
constexpr int kDirectionSlot = kSlotsPerHit;
/// The attached camera ray over its local parameters: the hit triangle's three vertex positions
/// (column 3 i + j: vertex i along axis j).
constexpr int kWarpLocal = 9;
using CameraWarp = AttachedCameraRay<kWarpLocal>;

/// One chosen-shape hit of a path that scatters (seg < max depth), as traced.
struct TapeHit {
  Hit hit;
  Vec3 origin;     ///< the ray's origin (value)
  Vec3 direction;  ///< the ray's fixed direction
};

/// The hits of the current pass of a path. Hits window .. window + capacity - 1 hold slots.
struct Tape {
  std::vector<TapeHit> hits;
  int window = 0;
  /// Hits with slots in this pass: kHitsPerPass, or 1 in a first pass whose camera direction
  /// holds the second hit's slots (kDirectionSlot).
  int capacity = kHitsPerPass;
  bool moving = false;  ///< a chosen-shape hit at or before the current vertex: p moves
  void reset(int first) {
    hits.clear();
    window = first;
    capacity = kHitsPerPass;
    moving = false;
  }
};

/// The geometry view of a reverse-mode pass: vertices and normals are constants (zero
/// derivatives); attach() (called by trace_path after each hit) records chosen-shape hits that
/// scatter and gives those in the pass's window unit derivatives in their slots, on top of the
/// derivatives p and ns carry from the earlier hits through the ray origin.
struct ReverseView {
  using Real = RDual;
  const Scene* scene;
  const std::vector<bool>* chosen;
  Tape* tape;
  Vec3T<Real> position(int shape, int v) const { return lift<Real>(scene->shapes[shape].mesh.positions[v]); }
  Vec3T<Real> normal(int shape, int v) const { return lift<Real>(scene->shapes[shape].mesh.normals[v]); }
  /// Always true: the path goes on (trace_path's attach contract).
  bool attach(SurfaceInteraction<Real>& si, const Hit& hit, const Vec3& o, const Vec3& d, bool scatters) const {
    if (!scatters || !(*chosen)[size_t(si.shape)]) return true;
    tape->moving = true;
    const int slot = (int(tape->hits.size()) - tape->window) * kSlotsPerHit;
    tape->hits.push_back({hit, o, d});
    if (slot < 0 || slot >= tape->capacity * kSlotsPerHit) return true;
    for (int i = 0; i < 3; ++i) {
      si.p[i].derivatives()[slot + i] += 1.0;
      si.ns[i].derivatives()[slot + 3 + i] += 1.0;
    }
    return true;
  }
};

/// The view of reverse mode's probe pass: doubles, sampling as a derivative path does
/// (kDerivativeSampling: the same random numbers give ReverseView's path), stopping at the first
/// chosen-shape hit that scatters. A path without one has no interior derivative (no vertex of
/// it moves) and its boundary term moves edges only, so its probe pass is the whole sample and
/// needs no duals; the other paths are traced again with ReverseView, whose boundary term takes
/// over the probe's stream at the first chosen-shape hit. On a scene where the chosen shapes fill
/// a small part of the image, most paths skip the dual arithmetic.
struct ProbeView : PrimalView {
  static constexpr bool kDerivativeSampling = true;
  const std::vector<bool>* chosen;
  bool* stopped;  ///< set when the path met a chosen-shape hit that scatters
  bool attach(SurfaceInteraction<Real>& si, const Hit&, const Vec3&, const Vec3&, bool scatters) const {
    if (!scatters || !(*chosen)[size_t(si.shape)]) return true;
    *stopped = true;
    return false;
  }
};

/// The view of a hit's local Jacobian: the three vertices of triangle `tri` carry unit
/// derivatives, positions in slots 3k..3k+2 and normals in 9+3k..9+3k+2 (k = the vertex's place).
struct HitJacobianView {
  using Real = LDual;
  const Scene* scene;
  Eigen::Vector3i tri;
  int place(int v) const { return v == tri[0] ? 0 : (v == tri[1] ? 1 : 2); }
  Vec3T<Real> unit(const Vec3& x, int first) const {
    Eigen::Matrix<double, 3, kLocal> m = Eigen::Matrix<double, 3, kLocal>::Zero();
    m.block<3, 3>(0, first) = Mat3::Identity();
    return lift<kLocal>(x, m);
  }
  Vec3T<Real> position(int shape, int v) const {
    return unit(scene->shapes[size_t(shape)].mesh.positions[size_t(v)], 3 * place(v));
  }
  Vec3T<Real> normal(int shape, int v) const {
    return unit(scene->shapes[size_t(shape)].mesh.normals[size_t(v)], 9 + 3 * place(v));
  }
};

/// Gradient contributions of one sample, committed to its tile only when all are finite.
struct Contribution {
  int chosen;  ///< index into ReverseConfig::shapes
  int vertex;
  bool normal;  ///< adjoint of the vertex normal (else of the position)
  Vec3 value;
};

/// Sums of one tile (or of the whole run): dL/dx and dL/dN per (chosen shape, vertex).
struct Accumulator {
  std::unordered_map<uint64_t, Vec3> position, normal;
  static uint64_t key(int chosen, int vertex) { return (uint64_t(uint32_t(chosen)) << 32) | uint32_t(vertex); }
  void add(const Contribution& c) {
    auto& map = c.normal ? normal : position;
    auto [it, inserted] = map.try_emplace(key(c.chosen, c.vertex), c.value);
    if (!inserted) it->second += c.value;
  }
};

/// The adjoint of an edge's end velocities, `g0` and `g1` (the derivative of the loss with respect
/// to the velocity of end 0 and end 1, world), carried to the vertices that move the ends:
/// `add(chosen, vertex, value)` for each chosen shape's vertex (chosen_index[shape] >= 0). A mesh
/// edge's ends are its vertices v0 and v1; an end of an intersection-curve segment moves with up
/// to five vertices of the two crossing triangles, through its Jacobian (CrossingEnd): vertex i
/// gets J_i^T g.
template <class Add>
void add_edge_adjoint(const edgetree::Edge& e, const Vec3& g0, const Vec3& g1,
                      const std::vector<int>& chosen_index, Add&& add) {
  if (e.crossing) {
    for (int k = 0; k < 2; ++k) {
      const edgetree::CrossingEnd& end = e.crossing->ends[size_t(k)];
      const Vec3& g = k == 0 ? g0 : g1;
      for (int i = 0; i < 5; ++i) {
        const edgetree::VertexRef& r = end.vertices[size_t(i)];
        if (r.shape < 0 || r.shape >= int(chosen_index.size())) continue;
        const int ci = chosen_index[size_t(r.shape)];
        if (ci >= 0) add(ci, r.vertex, Vec3(end.jacobian.middleCols<3>(3 * i).transpose() * g));
      }
    }
    return;
  }
  if (e.shape < 0 || e.shape >= int(chosen_index.size())) return;
  const int ci = chosen_index[size_t(e.shape)];
  if (ci < 0) return;
  add(ci, e.v0, g0);
  add(ci, e.v1, g1);
}

/// The secondary boundary term of a reverse-mode pass (the reverse of BoundaryHook): the edge's
/// share goes to the sample's contribution list (first pass only), p's share to L's slots. Real
/// is RDual (ReverseView) or double (ProbeView: p does not move, p's share is zero).
template <class Real>
struct ReverseBoundaryHook : BoundaryHookBase {
  const Tape* tape;
  const std::vector<int>* chosen_index;  ///< per shape: its index in the chosen list, or -1
  Color adjoint;                         ///< the pixel's adjoint / spp
  bool edges;                            ///< add the edge vertices' share (first pass of the path)
  std::vector<Contribution>* out;
  /// Skip the vertices before the path's first chosen-shape hit (tape->moving false): a probe
  /// pass did them, and `sampler` continues where the probe's stream stopped.
  bool after_probe = false;
  /// Where the boundary samples' counters go; null: trace_path's (the path's) counters.
  PathStats* stats_out = nullptr;

  void operator()(const SurfaceInteraction<Real>& si, const ShadingPoint<Real>& sp, const Vec3& wo_local,
                  const ColorT<Real>& beta, int seg, Sampler&, PathStats& path_stats, ColorT<Real>& L) const {
    if (after_probe && !tape->moving) return;
    PathStats& stats = stats_out ? *stats_out : path_stats;
    constexpr bool duals = !std::is_same_v<Real, double>;
    Eigen::Matrix<double, 3, kSlots> dp = Eigen::Matrix<double, 3, kSlots>::Zero();
    if constexpr (duals)
      for (int i = 0; i < 3; ++i) dp.row(i) = si.p[i].derivatives().transpose();
    edgetree::SilhouetteQuery q = boundary_query(*boundary_ctx, si, sp, wo_local, scratch);
    q.eligible = tape->moving ? &boundary_ctx->all : &boundary_ctx->moving;
    q.velocities = nullptr;  // a parameter per vertex: no normal-velocity factor
    for_each_boundary_sample(
        *ctx, *boundary_ctx, vertex(si, sp, q, wo_local, beta, seg), *sampler, stats,
        [](const edgetree::Edge&, double, const Vec3&) { return true; },
        [&](const edgetree::Edge& e, double t, const Color& weight, const Vec3& g) {
          // p's share: J = g . (v_edge - dp), the -g . dp part through L's slots.
          if constexpr (duals) {
            const Eigen::Matrix<double, 1, kSlots> Jp = -(g.transpose() * dp);
            if (!Jp.isZero(0.0))
              for (int c = 0; c < 3; ++c) L[c] += RDual(0.0, (weight[c] * Jp).transpose());
          }
          // The edge's share: its ends' velocities, (1 - t) v0 + t v1.
          if (edges) {
            const double a = (adjoint * weight).sum();
            add_edge_adjoint(e, Vec3(a * (1 - t) * g), Vec3(a * t * g), *chosen_index,
                             [&](int ci, int vertex, const Vec3& value) {
                               out->push_back({ci, vertex, false, value});
                             });
          }
        });
  }
};

bool finite(const std::vector<Contribution>& cs) {
  for (const Contribution& c : cs)
    if (!c.value.allFinite()) return false;
  return true;
}

/// What one tile of the interior and secondary boundary terms adds up; tiles are combined in
/// tile order, so the sums do not depend on the thread count.
struct TileSums {
  Accumulator acc;
  PathStats stats;
  double loss = 0;
  uint64_t nonfinite = 0, replays = 0, probed = 0;
};

/// What one tile's samples reuse from one to the next: the hit tape, the vertex adjoints of a
/// sample, and the edge choice's scratch (one tile runs on one thread at a time).
struct TileScratch {
  Tape tape;
  std::vector<Contribution> contributions;
  edgetree::EdgeChoiceScratch edge_choice;
  /// The boundary term's stream where a probe pass stopped (at the path's first chosen-shape hit
  /// that scatters): the dual passes of the sample continue it from there. Set whenever the probe
  /// stopped; unused by a sample without traversals (its passes build no boundary hook).
  std::optional<Sampler> resume;
  /// The attached camera ray of the sample's first pass (moves false: detached) and its hit.
  CameraWarp warp = CameraWarp::detached(Vec3::UnitZ());
  Hit warp_hit;
};

/// One sample of one pixel: sample index s of pixel (x, y), and the run's seed.
struct PixelSample {
  int x, y, s;
  uint64_t seed;
};

/// A hash of what a set-up depends on and an optimiser changes: the film size and every shape's
/// positions and triangles (FNV-1a over their bytes).
uint64_t meshes_fingerprint(const Scene& scene) {
  uint64_t h = fnv1a(&scene.camera.width, sizeof(scene.camera.width));
  h = fnv1a(&scene.camera.height, sizeof(scene.camera.height), h);
  for (const Shape& s : scene.shapes) {
    h = fnv1a(s.mesh.positions.data(), s.mesh.positions.size() * sizeof(Vec3), h);
    h = fnv1a(s.mesh.triangles.data(), s.mesh.triangles.size() * sizeof(s.mesh.triangles[0]), h);
  }
  return h;
}

/// Throws qsil::Error unless `adjoint` holds width x height x 3 finite weights (names the pixel).
void check_adjoint(const std::vector<double>& adjoint, int width, int height) {
  const size_t expected = size_t(width) * size_t(height) * 3;
  if (adjoint.size() != expected)
    throw Error("adjoint image: expected " + std::to_string(width) + " x " + std::to_string(height) +
                " x 3 = " + std::to_string(expected) + " values (got " + std::to_string(adjoint.size()) + ")");
  for (size_t i = 0; i < adjoint.size(); ++i)
    if (!std::isfinite(adjoint[i]))
      throw Error("adjoint image: non-finite weight at pixel (" + std::to_string((i / 3) % size_t(width)) + ", " +
                  std::to_string((i / 3) / size_t(width)) + ")");
}

}  // namespace

class ReverseEstimator::Impl : public RenderSetup {
 public:
  Impl(const Scene& s, ReverseConfig c)
      : RenderSetup(s), scene(s), config(std::move(c)), fingerprint(meshes_fingerprint(s)) {
    check_sample_rates(s.camera, config.sppi, config.sppp);
    if (config.shapes.empty()) throw Error("reverse mode: no shape to differentiate");
    chosen.assign(s.shapes.size(), false);
    chosen_index.assign(s.shapes.size(), -1);
    for (size_t i = 0; i < config.shapes.size(); ++i) {
      const int sh = config.shapes[i];
      if (sh < 0 || sh >= int(s.shapes.size()))
        throw Error("reverse mode: shape index " + std::to_string(sh) + " out of range (the scene has " +
                    std::to_string(s.shapes.size()) + " shapes)");
      if (chosen[size_t(sh)]) throw Error("reverse mode: shape index " + std::to_string(sh) + " given twice");
      chosen[size_t(sh)] = true;
      chosen_index[size_t(sh)] = int(i);
    }
    if (config.method == Method::Regularized || config.method == Method::WarpedArea ||
        config.method == Method::Projective)
      throw Error("reverse mode: method " + std::string(method_name(config.method)) +
                  " is not supported (forward mode only: qsil grad)");
    if (config.method != Method::None && !samples_edges(config.method))
      throw Error("method " + std::string(method_name(config.method)) + " cannot estimate derivatives");
    check_camera_control_spp(config.camera_control_spp);
    if (samples_edges(config.method)) {
      boundary_ctx.camera_hits = config.camera_hits;
      set_up_boundary_term(s, tracer, config.method, nullptr, chosen, config.sppi, lights.environment, boundary,
                           boundary_ctx, primary, setup, config.intersection_curves);
      if (primary.attached && config.camera_control_spp > 0) {
        const auto t0 = std::chrono::steady_clock::now();
        setup.control_pixels = set_attached_control(ctx, primary.attachment, config.camera_control_spp);
        setup.control_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      }
    }
  }

  /// Adds the adjoints of the slots of tape hits [window, window + capacity) to `out` through
  /// each hit's local Jacobian.
  void backpropagate_hits(const Tape& tape, const ColorT<RDual>& L, const Color& a,
                          std::vector<Contribution>& out) const {
    const int last = std::min(int(tape.hits.size()), tape.window + tape.capacity);
    for (int h = tape.window; h < last; ++h) {
      const int slot = (h - tape.window) * kSlotsPerHit;
      Eigen::Matrix<double, kSlotsPerHit, 1> adj = Eigen::Matrix<double, kSlotsPerHit, 1>::Zero();
      for (int c = 0; c < 3; ++c) adj += a[c] * L[c].derivatives().segment<kSlotsPerHit>(slot);
      if (adj.isZero(0.0)) continue;
      const TapeHit& th = tape.hits[size_t(h)];
      const Shape& shape = scene.shapes[size_t(th.hit.shape)];
      const Eigen::Vector3i tri = shape.mesh.triangles[size_t(th.hit.triangle)];
      const HitJacobianView view{&scene, tri};
      const SurfaceInteraction<LDual> si =
          make_interaction(view, th.hit, lift<LDual>(th.origin), th.direction, tracer.local_origin());
      Eigen::Matrix<double, kLocal, 1> local = Eigen::Matrix<double, kLocal, 1>::Zero();
      for (int i = 0; i < 3; ++i) local += adj[i] * si.p[i].derivatives() + adj[3 + i] * si.ns[i].derivatives();
      const int ci = chosen_index[size_t(th.hit.shape)];
      // (A degenerate triangle repeating a vertex holds its derivatives at the first place.)
      for (int k = 0; k < 3; ++k) {
        out.push_back({ci, tri[k], false, Vec3(local.segment<3>(3 * k))});
        out.push_back({ci, tri[k], true, Vec3(local.segment<3>(9 + 3 * k))});
      }
    }
  }

  /// Whether the camera ray `ray` is attached (attached_camera.h): it hits a triangle of a chosen
  /// shape that the attachment touches.
  bool attached_hit(const CameraRay& ray) const {
    return primary.attached && ray.hit.valid() && chosen[size_t(ray.hit.shape)] &&
           primary.attachment.touches(scene, ray.hit.shape, ray.hit.triangle);
  }

  /// The attached camera ray of `ray` (attached_hit) at film position `film` in pixel (px, py),
  /// over the hit triangle's vertex positions (kWarpLocal): a unit velocity per coordinate.
  CameraWarp camera_warp(const CameraRay& ray, const Vec2& film, int px, int py) const {
    std::array<Eigen::Matrix<double, 3, kWarpLocal>, 3> unit;
    for (int i = 0; i < 3; ++i) {
      unit[size_t(i)].setZero();
      unit[size_t(i)].middleCols<3>(3 * i) = Mat3::Identity();
    }
    return attached_camera_warp<kWarpLocal>(scene, primary.attachment, ray, film, px, py, unit, kWarpLocal);
  }

  /// Adds the adjoints of an attached camera ray (`warp`, of hit `hit`) to `out`: the camera
  /// direction's slots (kDirectionSlot) of the first pass's L through the warp's d(direction)/dX,
  /// and sum_c a_c (L_c - c_c) times the Jacobian's d div(w V)/dX (AttachedCameraRay::apply_jacobian
  /// read backwards), X the hit triangle's vertex positions.
  void backpropagate_warp(const CameraWarp& warp, const Hit& hit, const ColorT<RDual>& L, const Color& a,
                          std::vector<Contribution>& out) const {
    Vec3 adj_dir = Vec3::Zero();
    double adj_jacobian = 0;
    for (int c = 0; c < 3; ++c) {
      adj_dir += a[c] * L[c].derivatives().segment<3>(kDirectionSlot);
      adj_jacobian += a[c] * (L[c].value() - warp.control[c]);
    }
    Eigen::Matrix<double, kWarpLocal, 1> local = adj_jacobian * warp.jacobian.derivatives();
    for (int i = 0; i < 3; ++i) local += adj_dir[i] * warp.dir[i].derivatives();
    const Eigen::Vector3i& tri = scene.shapes[size_t(hit.shape)].mesh.triangles[size_t(hit.triangle)];
    const int ci = chosen_index[size_t(hit.shape)];
    for (int k = 0; k < 3; ++k) out.push_back({ci, tri[k], false, Vec3(local.segment<3>(3 * k))});
  }

  /// The index of pixel (x, y) in the film (row-major): its adjoint's place, and the seed of its
  /// samples' streams.
  uint64_t pixel_index(int x, int y) const { return uint64_t(y) * uint64_t(scene.camera.width) + uint64_t(x); }
  uint64_t pixel_index(const PixelSample& ps) const { return pixel_index(ps.x, ps.y); }

  /// The boundary term's stream of sample `ps` from its start (its second stream).
  Sampler boundary_stream(const PixelSample& ps) const {
    return qsil::boundary_stream(ps.seed, pixel_index(ps), uint64_t(ps.s));
  }

  /// How one pass runs the secondary boundary term (ReverseBoundaryHook's fields of the same names).
  struct BoundaryPass {
    bool edges;            ///< add the edge vertices' share (the path's first pass)
    bool after_probe;      ///< skip the vertices before the first chosen-shape hit
    PathStats* stats_out;  ///< the boundary samples' counters (null: the path's)
  };

  /// Sample `ps`'s path through `view` from the sample's first random number (every pass draws the
  /// same numbers: the same path; its camera ray and path counted in `st`), with the secondary
  /// boundary term (ReverseBoundaryHook<Real>: adjoint `a`, edges' shares to
  /// `scratch.contributions`, its stream `bsampler`, left where the path ends; run as `pass` says)
  /// when the sample has traversals. The part trace_probe and trace_pass share. An attached camera
  /// ray (attached_hit) stops the probe (ProbeView: radiance 0, `stopped` set) and, in the first
  /// pass with duals (tape window 0), sets scratch.warp and starts the path along the warped
  /// direction, whose slots are kDirectionSlot's (tape capacity 1).
  template <class View>
  ColorT<typename View::Real> trace_sample(const PixelSample& ps, const View& view, const Color& a, Sampler& bsampler,
                                           const BoundaryPass& pass, TileScratch& scratch, PathStats& st) const {
    using Real = typename View::Real;
    const Camera& cam = scene.camera;
    const uint64_t pixel = pixel_index(ps);
    Sampler sampler(ps.seed, pixel, uint64_t(ps.s));
    const Vec2 u = sampler.next2();
    const CameraRay ray = trace_camera_ray(ctx, ps.x, ps.y, u, st);
    PathRay<Real> start{lift<Real>(cam.origin()), ray.dir, ray.hit};
    Vec3T<Real> warped;  // the attached camera direction, its value ray.dir
    if (attached_hit(ray)) {
      if constexpr (std::is_same_v<View, ProbeView>) {
        *view.stopped = true;
        return lift<Real>(Color::Zero().eval());
      } else if (scratch.tape.window == 0) {
        scratch.warp = camera_warp(ray, Vec2(ps.x + u.x(), ps.y + u.y()), ps.x, ps.y);
        scratch.warp_hit = ray.hit;
        if (scratch.warp.moves) {
          Eigen::Matrix<double, 3, kSlots> slots = Eigen::Matrix<double, 3, kSlots>::Zero();
          slots.middleCols<3>(kDirectionSlot) = Mat3::Identity();
          warped = lift<kSlots>(ray.dir, slots);
          start.moving_dir = &warped;
          scratch.tape.capacity = 1;
        }
      }
    }
    const int traversals =
        boundary.sampler ? boundary_traversals(boundary_ctx.sppi, ps.seed, pixel, uint64_t(ps.s)) : 0;
    if (traversals <= 0) return trace_path(ctx, view, start, sampler, st);
    ReverseBoundaryHook<Real> hook{{&ctx, &boundary_ctx, &bsampler, traversals, &scratch.edge_choice},
                                   &scratch.tape,
                                   &chosen_index,
                                   a,
                                   pass.edges,
                                   &scratch.contributions};
    hook.after_probe = pass.after_probe;
    hook.stats_out = pass.stats_out;
    return trace_path(ctx, view, start, sampler, st, hook);
  }

  /// The probe pass of sample `ps` (ProbeView): the sample's path in doubles up to its first
  /// chosen-shape hit that scatters, with the secondary boundary term at the vertices before it
  /// (edges' shares to `scratch.contributions`, adjoint `a`; the boundary samples' counters to
  /// `st`). Returns the path's radiance when there is no such hit: this pass is then the whole
  /// sample, and its path's counters go to `st` too. Otherwise returns nothing and leaves the
  /// boundary term's stream in `scratch.resume`: the caller traces the sample with duals
  /// (trace_pass), which draws the path's numbers again and continues the boundary term from
  /// that hit on (the vertices before it do not move: their terms are what this pass added).
  std::optional<Color> trace_probe(const PixelSample& ps, const Color& a, TileScratch& scratch, PathStats& st) const {
    scratch.tape.reset(0);
    scratch.resume.reset();
    PathStats path_stats;  // the dual pass counts the path's rays itself if the probe stops
    bool stopped = false;
    const ProbeView view{{&scene}, &chosen, &stopped};
    Sampler bsampler = boundary_stream(ps);
    const Color L = trace_sample(ps, view, a, bsampler, {.edges = true, .after_probe = false, .stats_out = &st},
                                 scratch, path_stats);
    if (stopped) {
      scratch.resume = bsampler;
      return std::nullopt;
    }
    st += path_stats;
    return L;
  }

  /// One pass of sample `ps`'s path (trace_sample) with duals: slots for tape hits [window,
  /// window + capacity) (and, in the first pass of an attached camera hit, for the camera
  /// direction: backpropagate_warp), its secondary boundary term adding to `scratch.contributions` (adjoint
  /// `a` of the pixel, per sample; the edges' share on the first pass; after a probe pass stopped,
  /// only from the first chosen-shape hit on, drawing from a copy of `scratch.resume`) and its
  /// hits' adjoints added by backpropagate_hits.
  ColorT<RDual> trace_pass(const PixelSample& ps, int window, const Color& a, TileScratch& scratch,
                           PathStats& st) const {
    scratch.tape.reset(window);
    scratch.warp.moves = false;
    const ReverseView view{&scene, &chosen, &scratch.tape};
    Sampler bsampler = scratch.resume ? *scratch.resume : boundary_stream(ps);
    const BoundaryPass pass{.edges = window == 0, .after_probe = scratch.resume.has_value(), .stats_out = nullptr};
    const ColorT<RDual> L = trace_sample(ps, view, a, bsampler, pass, scratch, st);
    backpropagate_hits(scratch.tape, L, a, scratch.contributions);
    if (scratch.warp.moves) backpropagate_warp(scratch.warp, scratch.warp_hit, L, a, scratch.contributions);
    return L;
  }

  /// The interior and secondary boundary terms of samples [first, first + count) of the pixels of
  /// `tile`: each sample's path is traced once per window of kHitsPerPass tape hits (the first
  /// window one hit when the camera direction holds the second's slots); a sample
  /// with a non-finite radiance or adjoint is dropped and counted. Writes the pixels' primal
  /// values into `image` (W x H x 3).
  void reverse_tile(const Tile& tile, const std::vector<double>& adjoint, int first, int count, uint64_t seed,
                    TileSums& sums, std::vector<double>& image) const {
    TileScratch scratch;
    std::vector<Contribution>& contributions = scratch.contributions;
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        const uint64_t pixel = pixel_index(x, y);
        const Color a = Eigen::Map<const Color>(&adjoint[3 * pixel]) / double(count);
        Color sum = Color::Zero();
        for (int s = first; s < first + count; ++s) {
          contributions.clear();
          const PixelSample ps{x, y, s, seed};
          std::optional<Color> probed;
          if (config.probe_paths) probed = trace_probe(ps, a, scratch, sums.stats);
          Color value_L;
          if (probed) {
            value_L = *probed;
            ++sums.probed;
          } else {
            value_L = value(trace_pass(ps, 0, a, scratch, sums.stats));
            // The next window starts after the first pass's hits with slots (one when the camera
            // direction held the second's).
            for (int w = scratch.tape.capacity; w < int(scratch.tape.hits.size()); w += kHitsPerPass) {
              trace_pass(ps, w, a, scratch, sums.stats);
              ++sums.replays;
            }
          }
          if (!value_L.allFinite() || !finite(contributions)) {
            ++sums.nonfinite;
            continue;
          }
          sum += value_L;
          for (const Contribution& c : contributions) sums.acc.add(c);
        }
        for (int c = 0; c < 3; ++c) image[3 * pixel + size_t(c)] = sum[c] / count;
        sums.loss += (Eigen::Map<const Color>(&adjoint[3 * pixel]) * sum).sum() / count;
      }
  }

  /// The primary boundary term: the camera's edge samples of samples [first, first + count),
  /// weighted by their pixel's adjoint, added to `d_position` and to r's counters.
  void add_primary_term(const std::vector<double>& adjoint, int first, int count, const RenderOptions& options,
                        std::vector<std::vector<Vec3>>& d_position, ReverseResult& r) const {
    const size_t W = size_t(scene.camera.width);
    PathStats st;
    std::vector<Contribution> flux;  // a sample's attached flux, added when all of it is finite
    for_each_primary_sample(ctx, primary, config.sppp, first, count, options.seed, options.threads, st,
                            [&](const PrimarySample& ps) {
                              const size_t pixel = size_t(ps.py) * W + size_t(ps.px);
                              const double a = (Eigen::Map<const Color>(&adjoint[3 * pixel]) * ps.weight).sum() / count;
                              const Vec3 g0 = a * (1 - ps.t) * ps.g, g1 = a * ps.t * ps.g;
                              if (!g0.allFinite() || !g1.allFinite()) {
                                ++r.nonfinite;
                                return;
                              }
                              flux.clear();
                              if (ps.attached) {
                                const Color adj = Eigen::Map<const Color>(&adjoint[3 * pixel]) / double(count);
                                for_each_attached_side(
                                    scene, primary.attachment, ps.sides, ps.point(), ps.film, ps.px, ps.py,
                                    [&](const EdgeSides::Side& side, double k, const Color& L) {
                                      const int ci = chosen_index[size_t(side.hit.shape)];
                                      if (ci < 0) return;
                                      // The flux - k (L - c) (g . v_side), v_side = sum_i b_i v_i.
                                      const Vec3 gs = -ps.scale * k * (adj * L).sum() * ps.g;
                                      const Eigen::Vector3i& tri = scene.shapes[size_t(side.hit.shape)]
                                                                       .mesh.triangles[size_t(side.hit.triangle)];
                                      const double b[3] = {1 - side.hit.u - side.hit.v, side.hit.u, side.hit.v};
                                      for (int i = 0; i < 3; ++i) flux.push_back({ci, tri[i], false, Vec3(b[i] * gs)});
                                    });
                                if (!finite(flux)) {
                                  ++r.nonfinite;
                                  return;
                                }
                              }
                              add_edge_adjoint(*ps.edge, g0, g1, chosen_index, [&](int ci, int vertex, const Vec3& value) {
                                d_position[size_t(ci)][size_t(vertex)] += value;
                              });
                              for (const Contribution& c : flux)
                                d_position[size_t(c.chosen)][size_t(c.vertex)] += c.value;
                            });
    r.rays += st.rays;
    r.traversals += st.boundary_traversals;
    r.zero_traversals += st.boundary_zero;
  }

  const Scene& scene;
  ReverseConfig config;
  /// False after an update() that threw: the structures may not match the scene (run refuses,
  /// the next update sets up anew).
  bool valid = true;
  /// meshes_fingerprint of the scene as set up or last updated: run and render refuse another.
  uint64_t fingerprint;

  /// Throws qsil::Error unless the set-up is valid and the scene's meshes and film size are those
  /// it was set up or last updated for.
  void check_current() const {
    if (!valid) throw Error("reverse mode: the last update() failed; call update() again");
    if (meshes_fingerprint(scene) != fingerprint)
      throw Error("reverse mode: the scene's meshes or film size changed since the set-up or the last update(); "
                  "call update() first");
  }
  std::vector<bool> chosen;
  std::vector<int> chosen_index;
  SetupReport setup;
};

ReverseEstimator::ReverseEstimator(const Scene& scene, ReverseConfig config) {
  const auto t0 = std::chrono::steady_clock::now();
  impl_ = std::make_unique<Impl>(scene, std::move(config));
  impl_->setup.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
ReverseEstimator::~ReverseEstimator() = default;
ReverseEstimator::ReverseEstimator(ReverseEstimator&&) noexcept = default;
ReverseEstimator& ReverseEstimator::operator=(ReverseEstimator&&) noexcept = default;
ReverseUpdate ReverseEstimator::update() {
  Impl& m = *impl_;
  const auto t0 = std::chrono::steady_clock::now();
  ReverseUpdate out;
  const bool failed_before = !m.valid;
  m.valid = false;  // until this update has finished
  // A fresh set-up would take another local origin: set up anew, so that the estimates stay those
  // of a new estimator's (the local origin rounds Embree's float geometry).
  const bool origin_moved = embree_local_origin(m.scene) != m.tracer.local_origin();
  if (failed_before || origin_moved || !m.tracer.update_meshes(m.scene)) {
    // Another topology (a remeshing), another local origin, or a failed update: set up anew.
    impl_ = std::make_unique<Impl>(m.scene, m.config);
    out.reason = failed_before  ? "the last update failed: set up anew"
                 : origin_moved ? "the scene's bounds moved Embree's local origin: set up anew"
                                : "vertex or triangle counts changed: set up anew";
    out.seconds = out.edge_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    impl_->setup.seconds = out.seconds;
    return out;
  }
  m.lights.area_lights = AreaLights(m.scene);
  m.ctx = m.lights.context(m.scene, m.tracer);
  if (samples_edges(m.config.method)) {
    const auto te = std::chrono::steady_clock::now();
    // The control variate's c: kept (ReverseConfig::camera_control_spp), the primary edges and
    // their attachment being found anew.
    std::vector<Color> control = std::move(m.primary.attachment.control);
    const int control_width = m.primary.attachment.control_width;
    const edgetree::RefitReport r =
        update_boundary_term(m.scene, m.tracer, m.config.method, m.chosen, m.lights.environment, m.boundary,
                             m.boundary_ctx, m.primary, m.setup, m.config.intersection_curves);
    // Without a c to keep (nothing was attached at the set-up, or the film's size changed), the
    // first update that attaches something runs the pre-pass.
    const size_t pixels = size_t(m.scene.camera.width) * size_t(m.scene.camera.height);
    if (!m.primary.attached) {
      m.setup.control_pixels = 0;
    } else if (control_width == m.scene.camera.width && control.size() == pixels) {
      m.primary.attachment.control = std::move(control);
      m.primary.attachment.control_width = control_width;
    } else if (m.config.camera_control_spp > 0) {
      const auto tc = std::chrono::steady_clock::now();
      m.setup.control_pixels = set_attached_control(m.ctx, m.primary.attachment, m.config.camera_control_spp);
      m.setup.control_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - tc).count();
    } else {
      m.setup.control_pixels = 0;
    }
    out.edge_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - te).count();
    out.refitted = !r.rebuild_advised();
    if (out.refitted) {
      out.box_growth = r.box_growth;
    } else {
      out.reason = !r.refitted ? r.reason
                   : r.box_growth > edgetree::kRefitMaxBoxGrowth
                       ? "box growth " + std::to_string(r.box_growth)
                       : std::to_string(r.retired + r.unflattened) + " edges promoted to creases";
    }
  } else {
    out.reason = "no boundary term";
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  m.setup.seconds = out.seconds;
  m.fingerprint = meshes_fingerprint(m.scene);
  m.valid = true;
  return out;
}

const ReverseConfig& ReverseEstimator::config() const { return impl_->config; }
const SetupReport& ReverseEstimator::setup() const { return impl_->setup; }

ReverseResult ReverseEstimator::run(const std::vector<double>& adjoint, const RenderOptions& options) const {
  const Impl& m = *impl_;
  m.check_current();
  const Scene& scene = m.scene;
  const int W = scene.camera.width, H = scene.camera.height;
  check_adjoint(adjoint, W, H);
  const int count = sample_range_count(options, scene.camera);
  if (options.parts != 1) throw Error("reverse mode runs in one process (parts = 1)");
  const int first = options.first_sample;
  const auto t0 = std::chrono::steady_clock::now();

  ReverseResult r;
  r.width = W;
  r.height = H;
  r.spp = count;
  r.image.assign(adjoint.size(), 0.0);

  // ---- Interior and secondary boundary terms, per tile.
  std::vector<TileSums> tiles(size_t(tile_count(W, H)));
  for_each_tile(W, H, options.threads, options.progress ? "reverse" : "", [&](const Tile& tile) {
    m.reverse_tile(tile, adjoint, first, count, options.seed, tiles[size_t(tile.index)], r.image);
  });

  // ---- Sums in tile order (deterministic whatever the thread count). Within a tile, each
  // vertex's sum is in sample order; across tiles, in tile order (the maps' iteration order
  // changes neither).
  std::vector<std::vector<Vec3>> d_position(m.config.shapes.size()), d_normal(m.config.shapes.size());
  for (size_t i = 0; i < m.config.shapes.size(); ++i) {
    const size_t n = scene.shapes[size_t(m.config.shapes[i])].mesh.positions.size();
    d_position[i].assign(n, Vec3::Zero());
    d_normal[i].assign(n, Vec3::Zero());
  }
  for (const TileSums& t : tiles) {
    for (const auto& [key, v] : t.acc.position) d_position[key >> 32][key & 0xffffffffu] += v;
    for (const auto& [key, v] : t.acc.normal) d_normal[key >> 32][key & 0xffffffffu] += v;
    r.loss += t.loss;
    r.rays += t.stats.rays;
    r.traversals += t.stats.boundary_traversals;
    r.zero_traversals += t.stats.boundary_zero;
    r.nonfinite += t.nonfinite;
    r.replays += t.replays;
    r.probed += t.probed;
  }

  if (m.boundary.sampler) m.add_primary_term(adjoint, first, count, options, d_position, r);

  // ---- Vertex normals -> positions (area-weighted normals of the moving mesh).
  for (size_t i = 0; i < m.config.shapes.size(); ++i) {
    const Shape& shape = scene.shapes[size_t(m.config.shapes[i])];
    if (!shape.face_normals && !shape.mesh.normals.empty())
      vertex_normals_adjoint(shape.mesh, d_normal[i], d_position[i]);
  }
  r.gradient = std::move(d_position);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

RenderResult ReverseEstimator::render(const RenderOptions& options) const {
  const Impl& m = *impl_;
  m.check_current();
  const int count = sample_range_count(options, m.scene.camera);
  if (options.parts != 1) throw Error("reverse mode runs in one process (parts = 1)");
  RenderResult r;
  render_primal(m.scene, m, FilmLayout(0), options, options.first_sample, count, r);
  return r;
}

std::vector<int> resolve_shapes(const Scene& scene, const std::vector<std::string>& ids) {
  std::vector<int> out;
  std::set<int> seen;
  for (const std::string& id : ids) {
    const int s = scene.find_shape(id);
    if (s < 0) throw Error("--shape '" + id + "': no shape with this id in " + scene.file.string());
    if (!seen.insert(s).second) throw Error("--shape '" + id + "': given twice");
    out.push_back(s);
  }
  return out;
}

}  // namespace qsil
