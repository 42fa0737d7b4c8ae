/// @file bench_refit.cpp
/// Refit against rebuild of the edge forest (EdgeForest::refit; docs/architecture.md §11), a
/// table printer. For each OBJ given (default: the bundled spot, bunny and teapot, paths relative
/// to the repository root), with smooth shading (concave edges are creases, as a one-sided
/// shape's in a scene):
/// - set-up time: build and refit of the forest, 2 threads, best of 3, with the intersection
///   curves' own time in each (a refit finds them anew; a build finds them beside its trees):
///   a forest's first refit, which fills the curves' pair cache (CandidatePairCache), and a
///   refit from the cache (the vertices unmoved); and build and refit of a forest without
///   intersection curves; the forest's memory (EdgeForest::memory_bytes) per edge as built and
///   once refitted, and the difference per triangle (mostly the pair cache);
/// - quality along an optimisation-like trajectory: `steps` steps, each moving every vertex by a
///   smooth random displacement field of amplitude `amplitude` times the bounding-box diagonal
///   (three sines of random direction, frequency and phase per step: what a Large Steps update
///   looks like, not noise); after each step the forest is refitted in place and a forest is
///   built anew, and the table gives the refit's box growth (RefitReport::box_growth), its
///   retired and unflattened edges, and the false-accept share (accepted inner nodes whose patch
///   has no silhouette, over all accepted inner nodes; points uniform in a box 3x the mesh's size
///   and near the surface, tests/soundness_set.h's mix) of the refit and of the rebuilt forest,
///   the refit's and the build's time, and where the refit's curve search took its pairs
///   (its cache, or the broad phase); and both times' means over the trajectory.
/// Fixed seeds: the same table for the same build, timings aside.
/// With `--refits-only N` (a workload for `perf` and for side-by-side runs of two builds): per mesh,
/// one build, one refit that fills the pair cache, then N refits of the unmoved mesh from it, and
/// one line with their mean time, their curve search's, and the last refit's bound counts;
/// `--without-curves` builds and refits that forest without intersection curves.

#include "cli_parse.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/node_rejection.h"
#include "qsil/scene.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

using namespace qsil;
using namespace qsil::edgetree;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The best of `reps` wall times of f(), and what f() returned on that run (the intersection
/// curves' share of it).
std::pair<double, double> best_of(int reps, const std::function<double()>& f) {
  std::pair<double, double> best{1e30, 0.0};
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const double part = f();
    const double t = seconds_since(t0);
    if (t < best.first) best = {t, part};
  }
  return best;
}

/// Shading points: half uniform in a box 3x the mesh's size, half at 1e-3 .. 1e-1 of the diagonal
/// off a random triangle's centroid along its normal (either side).
std::vector<Vec3> probe_points(const TriangleMesh& m, int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Box3 b = m.bounds();
  std::vector<Vec3> pts;
  for (int i = 0; i < count; ++i) {
    if (i % 2 == 0) {
      pts.push_back(b.center() + 1.5 * Vec3((2 * u(rng) - 1) * b.extent().x(), (2 * u(rng) - 1) * b.extent().y(),
                                            (2 * u(rng) - 1) * b.extent().z()));
      continue;
    }
    const int f = int(u(rng) * m.num_triangles()) % m.num_triangles();
    const auto& t = m.triangles[size_t(f)];
    const Vec3 c = (m.positions[size_t(t[0])] + m.positions[size_t(t[1])] + m.positions[size_t(t[2])]) / 3.0;
    const double off = std::pow(10.0, -1.0 - 2.0 * u(rng)) * b.diagonal() * (u(rng) < 0.5 ? -1 : 1);
    pts.push_back(c + off * m.face_cross(f).normalized());
  }
  return pts;
}

/// False-accept share of the quadric test: accepted inner nodes without a silhouette over all
/// accepted inner nodes, ground truth bottom-up (a node has a silhouette iff a child does).
double false_accept_share(const EdgeForest& f, const std::vector<Vec3>& pts) {
  std::atomic<long long> accepted{0}, false_accepts{0};
  const int N = int(f.nodes().size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pts.size(), 8), [&](const auto& r) {
    std::vector<char> has(static_cast<size_t>(N));
    long long a = 0, fa = 0;
    for (size_t k = r.begin(); k != r.end(); ++k) {
      for (int i = N - 1; i >= 0; --i) {
        const ForestNode& n = f.node(i);
        if (n.is_leaf()) {
          has[size_t(i)] = leaf_has_silhouette(f, i, pts[k]);
          continue;
        }
        bool h = false;
        for (int c = n.first; c < n.first + n.count; ++c) h = h || has[size_t(c)];
        has[size_t(i)] = h;
        if (n.always() || !may_have_silhouette(f, i, pts[k])) continue;
        ++a;
        fa += !h;
      }
    }
    accepted += a;
    false_accepts += fa;
  });
  return accepted ? double(false_accepts.load()) / double(accepted.load()) : 0.0;
}

/// One optimisation-like step: every vertex moved by a smooth field of amplitude amp * diagonal.
void smooth_step(TriangleMesh& m, double amp, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 2.0 * kPi);
  const double d = m.bounds().diagonal();
  for (int k = 0; k < 3; ++k) {
    const Vec3 dir = Vec3(g(rng), g(rng), g(rng)).normalized();
    const Vec3 push = Vec3(g(rng), g(rng), g(rng)).normalized() * (amp * d / std::sqrt(3.0));
    const double freq = (2.0 + 4.0 * u(rng) / (2.0 * kPi)) / d, phase = u(rng);
    for (Vec3& p : m.positions) p += push * std::sin(freq * dir.dot(p) + phase);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> meshes;
  int steps = 10, points = 400, refits_only = 0;
  bool refits_without_curves = false;
  double amplitude = 0.002;
  CLI::App app{"bench_refit: edge-forest refit against rebuild, time and quality along a trajectory"};
  app.add_option("meshes", meshes, "OBJ files (default: spot, bunny, teapot; paths relative to the repository root)");
  app.add_option("--steps", steps, "steps of the trajectory")->check(CLI::Range(1, 1000));
  app.add_option("--amplitude", amplitude, "displacement per step, fraction of the diagonal")->check(CLI::Range(0.0, 1.0));
  app.add_option("--points", points, "shading points of the false-accept share")->check(CLI::Range(10, 1000000));
  app.add_option("--refits-only", refits_only,
                 "build once, then refit the unmoved mesh this many times (from the pair cache) and print "
                 "only their mean time: a workload for a profiler")
      ->check(CLI::Range(1, 100000));
  app.add_flag("--without-curves", refits_without_curves,
               "with --refits-only: a forest built and refitted without intersection curves");
  if (const auto code = qsil::cli::parse_arguments(app, argc, argv)) return *code;
  if (refits_without_curves && refits_only == 0) {
    std::fprintf(stderr, "bench_refit: --without-curves needs --refits-only\n");
    return 2;
  }
  if (meshes.empty())
    meshes = {"scenes/meshes/spot.obj", "scenes/meshes/bunny.obj", "scenes/stability/meshes/teapot.obj"};
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 2);
  for (const std::string& path : meshes) {
    TriangleMesh mesh;
    try {
      mesh = load_obj(path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_refit: %s\n", e.what());
      return 2;
    }
    const std::string name = std::filesystem::path(path).stem().string();
    ForestShapeInput in{&mesh, 0, false, CreaseSet::Concave};
    const auto span = std::span(&in, 1);
    if (refits_only > 0) {
      ForestOptions options;
      options.intersection_curves = !refits_without_curves;
      EdgeForest f = EdgeForest::build(span, options);
      f.refit(span);  // fills the pair cache
      double total = 0, curves = 0;
      RefitReport rr;
      for (int r = 0; r < refits_only; ++r) {
        rr = f.refit(span);
        if (!rr.refitted) {
          std::fprintf(stderr, "bench_refit: %s: %s\n", name.c_str(), rr.reason.c_str());
          return 1;
        }
        total += rr.seconds;
        curves += rr.crossing_seconds;
      }
      std::printf(
          "%s: %d refits from the pair cache, mean %.4f s (their curves' search %.4f s); the last refitted "
          "%d bounds, %d of them fitted anew\n",
          name.c_str(), refits_only, total / refits_only, curves / refits_only, rr.bounds, rr.refitted_fully);
      continue;
    }
    // ---- set-up time on the unmoved mesh
    EdgeForest forest;
    const auto [build, build_cross] = best_of(3, [&] {
      forest = EdgeForest::build(span);
      return forest.crossing_stats().seconds;
    });
    RefitReport rep;
    // A forest's first refit fills its intersection curves' pair cache (CandidatePairCache), the
    // next ones on unmoved vertices search from it: both timed, each the best of 3.
    double refit_fill = 1e30, refit_fill_cross = 0;
    size_t bytes_built = 0, bytes_refitted = 0;  // the forest's, before and after its first refit
    for (int r = 0; r < 3; ++r) {
      EdgeForest fresh = EdgeForest::build(span);
      bytes_built = fresh.memory_bytes();
      const auto t0 = std::chrono::steady_clock::now();
      rep = fresh.refit(span);
      const double t = seconds_since(t0);
      bytes_refitted = fresh.memory_bytes();
      if (t < refit_fill) std::tie(refit_fill, refit_fill_cross) = std::pair(t, rep.crossing_seconds);
    }
    forest.refit(span);
    const auto [refit, refit_cross] = best_of(3, [&] {
      rep = forest.refit(span);
      return rep.crossing_seconds;
    });
    // Without the curves: a forest built and refitted with them off (a build finds them beside
    // its trees, so subtracting their own time from the build's would be wrong).
    ForestOptions no_curves;
    no_curves.intersection_curves = false;
    EdgeForest bare;
    const double build_bare = best_of(3, [&] {
                                bare = EdgeForest::build(span, no_curves);
                                return 0.0;
                              }).first;
    const double refit_bare = best_of(3, [&] {
                                bare.refit(span);
                                return 0.0;
                              }).first;
    std::printf(
        "%s: %d triangles, %zu edges; build %.4f s (intersection curves %.4f s, found beside the trees), "
        "refit filling the curves' pair cache %.4f s (%.4f s), %.3f of the build, refit from it %.4f s (%.4f "
        "s), %.3f; without the curves: build %.4f s, refit %.4f s, %.3f\n",
        name.c_str(), mesh.num_triangles(), forest.edges().size() + forest.always_edges().size(), build, build_cross,
        refit_fill, refit_fill_cross, refit_fill / build, refit, refit_cross, refit / build, build_bare, refit_bare,
        refit_bare / build_bare);
    const size_t edges = forest.edges().size() + forest.always_edges().size();
    std::printf("%s: forest memory %.1f bytes per edge as built, %.1f once refitted (the pair cache: %.1f bytes per "
                "triangle)\n",
                name.c_str(), double(bytes_built) / double(edges), double(bytes_refitted) / double(edges),
                (double(bytes_refitted) - double(bytes_built)) / double(mesh.num_triangles()));
    // ---- quality along a trajectory
    std::printf("%5s %9s %8s %8s %8s %7s %9s %9s %8s %8s %6s\n", "step", "moved", "growth", "retired", "unflat",
                "advise", "FA-refit", "FA-build", "refit s", "build s", "pairs");
    double sum_refit = 0, sum_build = 0;
    std::mt19937_64 rng(7);
    const std::vector<Vec3> start = mesh.positions;
    for (int s = 1; s <= steps; ++s) {
      smooth_step(mesh, amplitude, rng);
      double moved = 0;
      for (size_t v = 0; v < start.size(); ++v) moved += (mesh.positions[v] - start[v]).squaredNorm();
      moved = std::sqrt(moved / double(start.size())) / mesh.bounds().diagonal();
      auto t0 = std::chrono::steady_clock::now();
      rep = forest.refit(span);
      const double tr = seconds_since(t0);
      if (!rep.refitted) {
        std::fprintf(stderr, "bench_refit: %s: %s\n", name.c_str(), rep.reason.c_str());
        return 1;
      }
      t0 = std::chrono::steady_clock::now();
      const EdgeForest rebuilt = EdgeForest::build(span);
      const double tb = seconds_since(t0);
      const std::vector<Vec3> pts = probe_points(mesh, points, unsigned(100 + s));
      sum_refit += tr;
      sum_build += tb;
      // Where the refit's curve search took its pairs from: its cache, or the broad phase.
      const char* pairs = forest.crossing_stats().from_cache ? "cache" : "search";
      std::printf("%5d %9.5f %8.3f %8d %8d %7s %9.3f %9.3f %8.4f %8.4f %6s\n", s, moved, rep.box_growth, rep.retired,
                  rep.unflattened, rep.rebuild_advised() ? "build" : "refit", false_accept_share(forest, pts),
                  false_accept_share(rebuilt, pts), tr, tb, pairs);
      std::fflush(stdout);
    }
    std::printf("%s: along the trajectory, refit %.4f s and build %.4f s on average: %.3f\n", name.c_str(),
                sum_refit / steps, sum_build / steps, sum_refit / sum_build);
  }
  return 0;
}
