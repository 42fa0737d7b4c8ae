/// @file bench_intersections.cpp
/// Intersection-curve benchmark (docs/architecture.md §11), a table printer: the time
/// find_intersection_curves takes (broad phase with Embree's rtcCollide, narrow phase with the
/// exact predicates) on generated meshes, with 1 and 2 threads (best of 3 each):
/// - `floor`: a perturbed icosphere (subdivision level --level, default 8: 1,310,720 triangles;
///   radius 1 with a smooth radial bump of 2 %) sunk 0.3 into a 4 x 4 floor of 2 triangles: the
///   sphere against the floor and against itself;
/// - `self`: the same sphere and a copy of it moved by 0.9 along x, in one mesh: two overlapping
///   parts crossing along a curve (a self-intersection of 2.6 M triangles).
/// Columns: triangles, candidate pairs (boxes overlap), crossing segments, seconds of Embree's BVH
/// build and of the whole (the exact tests run inside rtcCollide's callback), with 1 and 2
/// threads; and the peak resident memory of the process at the end.

#include "cli_parse.h"
#include "qsil/edgetree/intersection_curves.h"
#include "qsil/scene.h"

#include <sys/resource.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

using namespace qsil;
using namespace qsil::edgetree;

namespace {

/// An icosphere subdivided `level` times (20 * 4^level triangles, counter-clockwise outward),
/// radius 1 times 1 + 0.02 sin(5x) sin(7y) sin(3z).
TriangleMesh perturbed_sphere(int level) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh m;
  m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& p : m.positions) p.normalize();
  m.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back((m.positions[size_t(a)] + m.positions[size_t(b)]).normalized());
      return mid[key] = int(m.positions.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    next.reserve(4 * m.triangles.size());
    for (const Eigen::Vector3i& f : m.triangles) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
  for (Vec3& p : m.positions) p *= 1.0 + 0.02 * std::sin(5 * p.x()) * std::sin(7 * p.y()) * std::sin(3 * p.z());
  return m;
}

struct Timing {
  double build = 1e30, total = 1e30;
  IntersectionCurveStats stats;
  size_t segments = 0;
};

Timing best_of(const std::vector<CurveMesh>& meshes, int threads) {
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, size_t(threads));
  Timing t;
  for (int r = 0; r < 3; ++r) {
    IntersectionCurveStats st;
    const auto segs = find_intersection_curves(meshes, &st);
    t.build = std::min(t.build, st.build_seconds);
    t.total = std::min(t.total, st.seconds);
    t.stats = st;
    t.segments = segs.size();
  }
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  int level = 8;
  CLI::App app{"bench_intersections: intersection-curve times on a sunk and a self-intersecting sphere"};
  app.add_option("--level", level, "Icosphere subdivision level (8: 1,310,720 triangles)")->check(CLI::Range(1, 9));
  if (const auto code = qsil::cli::parse_arguments(app, argc, argv)) return *code;
  const TriangleMesh sphere = perturbed_sphere(level);
  TriangleMesh sunk = sphere;
  for (Vec3& p : sunk.positions) p.y() += 0.7;  // the floor y = 0 cuts it 0.3 deep
  TriangleMesh floor;
  floor.positions = {{-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2}};
  floor.triangles = {{0, 2, 1}, {0, 3, 2}};
  TriangleMesh two = sphere;
  const int n = two.num_vertices();
  for (int i = 0; i < n; ++i) two.positions.push_back(sphere.positions[size_t(i)] + Vec3(0.9, 0, 0));
  for (const Eigen::Vector3i& f : sphere.triangles) two.triangles.push_back(f + Eigen::Vector3i::Constant(n));
  std::printf("%-6s %9s %11s %9s | %8s %8s (1 thread) | %8s %8s (2 threads)\n", "case", "triangles", "candidates",
              "segments", "BVH", "total", "BVH", "total");
  struct Case {
    const char* name;
    std::vector<CurveMesh> meshes;
    int triangles;
  };
  for (const Case& c : {Case{"floor", {{&sunk, 0}, {&floor, 1}}, sunk.num_triangles() + 2},
                        Case{"self", {{&two, 0}}, two.num_triangles()}}) {
    const Timing one = best_of(c.meshes, 1), two_threads = best_of(c.meshes, 2);
    std::printf("%-6s %9d %11lld %9zu | %8.3f %8.3f            | %8.3f %8.3f\n", c.name, c.triangles,
                one.stats.candidate_pairs, one.segments, one.build, one.total, two_threads.build, two_threads.total);
    std::fflush(stdout);
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("peak resident memory: %.0f MiB\n", double(usage.ru_maxrss) / 1024.0);
  return 0;
}
