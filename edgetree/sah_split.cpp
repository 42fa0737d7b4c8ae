/// @file sah_split.cpp
/// Binned SAH split of edges [QSS 4.1].

#include "sah_split.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <vector>

namespace qsil::edgetree {

namespace {

/// Per-bucket edge counts and boxes.
struct Buckets {
  std::vector<int> cnt;
  std::vector<Box3> box;
  explicit Buckets(int b) : cnt(size_t(b), 0), box(size_t(b)) {}
};

void join(Box3& a, const Box3& b) { a.expand(b); }
void join(Buckets& a, const Buckets& b) {
  for (size_t k = 0; k < a.cnt.size(); ++k) {
    a.cnt[k] += b.cnt[k];
    a.box[k].expand(b.box[k]);
  }
}

/// `add`(edge, acc) over every edge into `identity`, in parallel when asked (the deterministic
/// reduction: the same chunks and joins whatever the threads do); T's join must be commutative and
/// associative (exactly, for finite coordinates: the result is the serial one).
template <class T, class Add>
T reduce(std::span<const EdgeBoxRef> edges, bool parallel, const T& identity, const Add& add) {
  if (!parallel) {
    T acc = identity;
    for (const auto& e : edges) add(e, acc);
    return acc;
  }
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<size_t>(0, edges.size(), 4096), identity,
      [&](const tbb::blocked_range<size_t>& r, T acc) {
        for (size_t i = r.begin(); i < r.end(); ++i) add(edges[i], acc);
        return acc;
      },
      [](T a, const T& b) {
        join(a, b);
        return a;
      });
}

double box_area(const Box3& b) {
  if (b.empty()) return 0.0;
  const Vec3 e = b.extent();
  return 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
}
}  // namespace

int sah_split(std::span<EdgeBoxRef> edges, int buckets, int parallel_from) {
  const int n = int(edges.size());
  // The two passes over a large range (the top levels, which a level's parallel loop does not
  // split) run in parallel: a box of exact minima and maxima (finite coordinates) and integer
  // counts do not depend on the order of their terms, so the split is the serial one.
  const bool parallel = n >= parallel_from;
  const Box3 cb = reduce(edges, parallel, Box3(), [](const EdgeBoxRef& e, Box3& b) { b.expand(0.5 * (e.lo + e.hi)); });
  int axis = 0;
  cb.extent().maxCoeff(&axis);
  const double lo = cb.lo[axis], ext = cb.hi[axis] - cb.lo[axis];
  auto median = [&]() {
    const int mid = n / 2;
    std::stable_sort(edges.begin(), edges.end(), [axis](const EdgeBoxRef& a, const EdgeBoxRef& b) {
      return a.lo[axis] + a.hi[axis] < b.lo[axis] + b.hi[axis];
    });
    return mid;
  };
  if (!(ext > 0.0)) return median();

  const int B = std::max(2, buckets);
  auto bucket_of = [&](const EdgeBoxRef& e) {
    const double c = 0.5 * (e.lo[axis] + e.hi[axis]);
    return std::clamp(int(B * ((c - lo) / ext)), 0, B - 1);
  };
  const auto [cnt, box] = reduce(edges, parallel, Buckets(B), [&](const EdgeBoxRef& e, Buckets& b) {
    const int k = bucket_of(e);
    b.cnt[k]++;
    b.box[k].expand(e.lo);
    b.box[k].expand(e.hi);
  });
  // Sweep: prefix from the left, suffix from the right.
  std::vector<double> left_cost(B, 0.0);
  std::vector<int> left_n(B, 0);
  Box3 acc;
  int accn = 0;
  for (int k = 0; k < B; ++k) {
    acc.expand(box[k]);
    accn += cnt[k];
    left_cost[k] = box_area(acc) * accn;
    left_n[k] = accn;
  }
  acc = Box3();
  accn = 0;
  double best = kInf;
  int best_k = -1;
  for (int k = B - 1; k >= 1; --k) {
    acc.expand(box[k]);
    accn += cnt[k];
    // split between bucket k-1 and k
    if (left_n[k - 1] == 0 || accn == 0) continue;
    const double c = left_cost[k - 1] + box_area(acc) * accn;
    if (c < best) {
      best = c;
      best_k = k;
    }
  }
  if (best_k < 0) return median();
  auto it = std::partition(edges.begin(), edges.end(), [&](const EdgeBoxRef& e) { return bucket_of(e) < best_k; });
  return int(it - edges.begin());
}

}  // namespace qsil::edgetree
